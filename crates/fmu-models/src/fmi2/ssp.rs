//! A population of pumps as an SSP file (System Structure and
//! Parameterization 1.0): `gearpump fmu --population CAMPAIGN.csv`.
//!
//! The `.ssp` is a zip archive with
//! * `SystemStructure.ssd`: one system, `Population`, with one component per
//!   pump sample, each the same `resources/GearPump.fmu` with a parameter
//!   binding to its parameter set (`prefix` = the component's name and a
//!   dot, so the set's names are `<sample>.<FMU variable>`);
//! * `resources/GearPump.fmu`: the pump FMU (of the design given);
//! * `resources/<sample>.ssv`: one parameter set per pump, its measured
//!   clearances (the FMU's parameters `tip_clearance_drive`,
//!   `tip_clearance_driven`, `bearing_clearance_drive`,
//!   `bearing_clearance_driven`, in m, the unit declared in the set); the
//!   lateral clearance, which a campaign does not measure, stays at the
//!   FMU's start value (the design's).
//!
//! The components have output connectors for `Q_out` and `torque` and no
//! input connectors: an importer that runs the system leaves the inputs at
//! their start values (1000 rpm, 30 bar, 60 degC) unless it connects them.
//! The file is written whole or not at all (a temporary file renamed).

use std::io::Write;
use std::path::Path;

/// One pump of the population: its sample id and its measured clearances,
/// m: tip (driving, driven), bearing (driving, driven).
#[derive(Debug, Clone, PartialEq)]
pub struct PopulationPump {
    pub sample: String,
    pub tip: [f64; 2],
    pub bearing: [f64; 2],
}

/// The FMU variable names of a pump's parameter set, in the order of
/// [`PopulationPump::values`].
pub const PARAMETERS: [&str; 4] = [
    "tip_clearance_drive",
    "tip_clearance_driven",
    "bearing_clearance_drive",
    "bearing_clearance_driven",
];

impl PopulationPump {
    /// The clearances in the order of [`PARAMETERS`], m.
    pub fn values(&self) -> [f64; 4] {
        [self.tip[0], self.tip[1], self.bearing[0], self.bearing[1]]
    }
}

/// Why a population could not be written.
#[derive(Debug, thiserror::Error)]
pub enum SspError {
    #[error("no pumps in the population")]
    Empty,
    #[error(
        "sample {0:?}: a sample id must be letters, digits, '_' or '-' (it names the SSP component and its parameter file)"
    )]
    BadName(String),
    #[error("sample {start:?}...: a sample id may have at most {max} characters, got {chars}")]
    LongName {
        /// The id's first characters.
        start: String,
        chars: usize,
        max: usize,
    },
    #[error("sample {0:?} appears twice")]
    Duplicate(String),
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{0}")]
    Zip(String),
}

const NS: &str = "xmlns:ssd=\"http://ssp-standard.org/SSP1/SystemStructureDescription\" \
                  xmlns:ssc=\"http://ssp-standard.org/SSP1/SystemStructureCommon\" \
                  xmlns:ssv=\"http://ssp-standard.org/SSP1/SystemStructureParameterValues\"";

/// The path of the FMU inside the SSP.
pub const FMU_RESOURCE: &str = "resources/GearPump.fmu";

fn plain(name: &str) -> bool {
    !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

/// A Real as text that reads back to the same value.
fn real(x: f64) -> String {
    format!("{x:e}")
}

/// The parameter set of one pump (`resources/<sample>.ssv`).
pub fn ssv(pump: &PopulationPump) -> String {
    let mut params = String::new();
    for (name, value) in PARAMETERS.iter().zip(pump.values()) {
        params.push_str(&format!(
            "    <ssv:Parameter name=\"{}.{name}\">\n      <ssv:Real value=\"{}\" unit=\"m\"/>\n    </ssv:Parameter>\n",
            pump.sample,
            real(value)
        ));
    }
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
<ssv:ParameterSet {NS} version=\"1.0\" name=\"{name}\">\n  <ssv:Parameters>\n{params}  </ssv:Parameters>\n\
  <ssv:Units>\n    <ssc:Unit name=\"m\">\n      <ssc:BaseUnit m=\"1\"/>\n    </ssc:Unit>\n  </ssv:Units>\n\
</ssv:ParameterSet>\n",
        name = pump.sample
    )
}

/// `SystemStructure.ssd` of the population (`name`, the campaign file's
/// stem, escaped for its XML attribute: a file name may hold `&`, `"` or
/// `<`; the sample ids are plain, [`check_pumps`]).
pub fn ssd(name: &str, pumps: &[PopulationPump]) -> String {
    let name = quick_xml::escape::escape(name);
    let mut elements = String::new();
    for p in pumps {
        elements.push_str(&format!(
            "      <ssd:Component name=\"{s}\" type=\"application/x-fmu-sharedlibrary\" source=\"{FMU_RESOURCE}\">\n\
        <ssd:Connectors>\n\
          <ssd:Connector name=\"Q_out\" kind=\"output\"><ssc:Real unit=\"m3/s\"/></ssd:Connector>\n\
          <ssd:Connector name=\"torque\" kind=\"output\"><ssc:Real unit=\"N.m\"/></ssd:Connector>\n\
        </ssd:Connectors>\n\
        <ssd:ParameterBindings>\n\
          <ssd:ParameterBinding type=\"application/x-ssp-parameter-set\" source=\"resources/{s}.ssv\" prefix=\"{s}.\"/>\n\
        </ssd:ParameterBindings>\n\
      </ssd:Component>\n",
            s = p.sample
        ));
    }
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
<ssd:SystemStructureDescription {NS} version=\"1.0\" name=\"{name}\">\n\
  <ssd:System name=\"Population\" description=\"One GearPump.fmu per pump sample, each with its measured clearances (resources/SAMPLE.ssv)\">\n\
    <ssd:Elements>\n{elements}    </ssd:Elements>\n  </ssd:System>\n\
  <ssd:DefaultExperiment startTime=\"0\" stopTime=\"1\"/>\n\
</ssd:SystemStructureDescription>\n"
    )
}

/// Checks the pumps as [`write_population_ssp`] does, without writing
/// anything: at least one, each sample id letters, digits, `_` or `-` and at
/// most `gearpump_core::limits::SAMPLE_ID_MAX_CHARS` characters, no id
/// twice. A caller checks with this before it builds the FMU.
pub fn check_pumps(pumps: &[PopulationPump]) -> Result<(), SspError> {
    if pumps.is_empty() {
        return Err(SspError::Empty);
    }
    let max = gearpump_core::limits::SAMPLE_ID_MAX_CHARS;
    for (i, p) in pumps.iter().enumerate() {
        let chars = p.sample.chars().count();
        if chars > max {
            return Err(SspError::LongName {
                start: p.sample.chars().take(16).collect(),
                chars,
                max,
            });
        }
        if !plain(&p.sample) {
            return Err(SspError::BadName(p.sample.clone()));
        }
        if pumps[..i].iter().any(|q| q.sample == p.sample) {
            return Err(SspError::Duplicate(p.sample.clone()));
        }
    }
    Ok(())
}

/// Writes the SSP of `pumps` with the FMU file `fmu` to `out` (see the
/// module docs); `name` is the system structure's name. Nothing is written
/// when a pump is refused ([`check_pumps`]), and the temporary file is
/// removed on every error.
pub fn write_population_ssp(
    out: &Path,
    name: &str,
    fmu: &Path,
    pumps: &[PopulationPump],
) -> Result<(), SspError> {
    check_pumps(pumps)?;
    let io = |path: &Path| {
        let path = path.display().to_string();
        move |source| SspError::Io { path, source }
    };
    let fmu_bytes = std::fs::read(fmu).map_err(io(fmu))?;
    let tmp = out.with_extension(format!("ssp.tmp-{}", std::process::id()));
    let zip_err = |e: zip::result::ZipError| SspError::Zip(format!("{}: {e}", tmp.display()));
    let write = || -> Result<(), SspError> {
        let file = std::fs::File::create(&tmp).map_err(io(&tmp))?;
        let mut z = zip::ZipWriter::new(file);
        let opts = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated);
        let mut add = |path: &str, bytes: &[u8]| -> Result<(), SspError> {
            super::package::check_zip_name(path)
                .map_err(|e| SspError::Zip(format!("{}: {e}", tmp.display())))?;
            z.start_file(path, opts).map_err(zip_err)?;
            z.write_all(bytes).map_err(io(&tmp))
        };
        add("SystemStructure.ssd", ssd(name, pumps).as_bytes())?;
        add(FMU_RESOURCE, &fmu_bytes)?;
        for p in pumps {
            add(&format!("resources/{}.ssv", p.sample), ssv(p).as_bytes())?;
        }
        z.finish().map_err(zip_err)?;
        Ok(())
    };
    let result = write().and_then(|()| std::fs::rename(&tmp, out).map_err(io(out)));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_checked_and_values_read_back() {
        let p = PopulationPump {
            sample: "N01".into(),
            tip: [28e-6, 32.1e-6],
            bearing: [12.9e-6, 15.3e-6],
        };
        let text = ssv(&p);
        assert!(text.contains("name=\"N01.tip_clearance_driven\""));
        assert!(text.contains(&format!("value=\"{}\"", real(32.1e-6))));
        assert_eq!(real(32.1e-6).parse::<f64>().unwrap(), 32.1e-6);
        let dir = std::env::temp_dir().join(format!("gearpump-ssp-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("p.ssp");
        let fmu = dir.join("x.fmu");
        std::fs::write(&fmu, b"not an fmu").unwrap();
        for (pumps, want) in [
            (vec![], "no pumps"),
            (
                vec![PopulationPump {
                    sample: "a.b".into(),
                    ..p.clone()
                }],
                "sample \"a.b\"",
            ),
            (vec![p.clone(), p.clone()], "twice"),
            (
                vec![PopulationPump {
                    sample: "N".repeat(65_600),
                    ..p.clone()
                }],
                "at most 64 characters, got 65600",
            ),
            (
                vec![PopulationPump {
                    sample: "N".repeat(65),
                    ..p.clone()
                }],
                "at most 64 characters, got 65",
            ),
        ] {
            let e = write_population_ssp(&out, "x", &fmu, &pumps).unwrap_err();
            assert!(e.to_string().contains(want), "{e}");
            assert!(e.to_string().len() < 200, "a short message: {e}");
            assert!(check_pumps(&pumps).is_err());
            assert!(!out.exists());
        }
        let longest = PopulationPump {
            sample: "N".repeat(gearpump_core::limits::SAMPLE_ID_MAX_CHARS),
            ..p.clone()
        };
        write_population_ssp(&out, "x", &fmu, std::slice::from_ref(&longest)).unwrap();
        assert!(out.is_file());
        // nothing but the SSP itself is left beside it
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
        write_population_ssp(&out, "x", &fmu, std::slice::from_ref(&p)).unwrap();
        assert!(out.is_file());
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A campaign file named with XML's special characters still gives a
    /// well-formed `SystemStructure.ssd` whose name reads back as the stem.
    #[test]
    fn the_system_name_is_escaped() {
        let p = PopulationPump {
            sample: "N01".into(),
            tip: [30e-6, 32e-6],
            bearing: [10e-6, 12e-6],
        };
        let stem = "a&b \"c\" <d>";
        let text = ssd(stem, &[p]);
        let mut reader = quick_xml::Reader::from_str(&text);
        let mut names = Vec::new();
        loop {
            match reader.read_event().expect("well-formed XML") {
                quick_xml::events::Event::Eof => break,
                quick_xml::events::Event::Start(e)
                    if e.name().as_ref() == b"ssd:SystemStructureDescription" =>
                {
                    let a = e
                        .try_get_attribute("name")
                        .unwrap()
                        .expect("a name attribute");
                    names.push(a.unescape_value().unwrap().into_owned());
                }
                _ => {}
            }
        }
        assert_eq!(names, [stem]);
    }
}
