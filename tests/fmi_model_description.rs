//! The committed `modelDescription/modelDescription.xml` is the one the
//! variable table generates (the table in `src/fmi2/pump.rs` is the single
//! source of truth). After changing the table, regenerate it with
//!
//! ```text
//! cargo run -p fmu-build --release -- --xml modelDescription/modelDescription.xml
//! ```
//!
//! (or run this test with `GEARPUMP_UPDATE_XML=1`), and change the GUID.

use std::path::Path;

use gearpump::fmi2::{check_model, model_description_xml, ExportedModel};

#[test]
fn committed_model_description_matches_the_variable_table() {
    check_model::<ExportedModel>().unwrap();
    let fresh = model_description_xml::<ExportedModel>();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("modelDescription/modelDescription.xml");
    if std::env::var_os("GEARPUMP_UPDATE_XML").is_some() {
        std::fs::write(&path, &fresh).unwrap();
    }
    let committed =
        std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    if committed != fresh {
        let line = committed
            .lines()
            .zip(fresh.lines())
            .position(|(a, b)| a != b)
            .unwrap_or_else(|| committed.lines().count().min(fresh.lines().count()));
        panic!(
            "{} differs from the variable table's XML from line {}:\n  committed: {:?}\n  generated: {:?}\n\
             regenerate it: cargo run -p fmu-build --release -- --xml modelDescription/modelDescription.xml",
            path.display(),
            line + 1,
            committed.lines().nth(line).unwrap_or("<end of file>"),
            fresh.lines().nth(line).unwrap_or("<end of file>"),
        );
    }
}

#[test]
fn model_description_has_the_fmu_contract() {
    // INTERFACES.md: names, causalities, units, display units.
    let xml = model_description_xml::<ExportedModel>();
    for needle in [
        r#"modelIdentifier="GearPump""#,
        r#"canHandleVariableCommunicationStepSize="true""#,
        r#"canGetAndSetFMUstate="true""#,
        r#"canSerializeFMUstate="true""#,
        r#"canBeInstantiatedOnlyOncePerProcess="false""#,
        r#"<DisplayUnit name="rpm""#,
        r#"<DisplayUnit name="bar""#,
        r#"<DisplayUnit name="degC""#,
        r#"<DisplayUnit name="l/min""#,
        r#"name="speed" valueReference="1""#,
        r#"unit="rad/s" displayUnit="rpm" start="104.71975511965977""#,
        r#"unit="Pa" displayUnit="bar" start="101325""#,
        r#"unit="Pa" displayUnit="bar" start="3101325""#,
        r#"unit="K" displayUnit="degC" start="333.15""#,
    ] {
        assert!(xml.contains(needle), "{needle} missing from\n{xml}");
    }
    let vars = <ExportedModel as gearpump::fmi2::CoSimModel>::variables();
    let find = |n: &str| {
        vars.iter()
            .find(|v| v.name == n)
            .unwrap_or_else(|| panic!("{n}"))
    };
    use gearpump::fmi2::Causality::*;
    for (n, c) in [
        ("speed", Input),
        ("p_in", Input),
        ("p_out", Input),
        ("T_oil", Input),
        ("Q_out", Output),
        ("Q_out_inst", Output),
        ("torque", Output),
        ("eta_v", Output),
        ("eta_hm", Output),
        ("V_delivered", Output),
        ("theta", Output),
        ("tip_clearance_drive", Parameter),
        ("tip_clearance_driven", Parameter),
        ("bearing_clearance_drive", Parameter),
        ("bearing_clearance_driven", Parameter),
        ("micromotion", Parameter),
    ] {
        assert_eq!(find(n).causality, c, "{n}");
    }
}
