//! The committed `modelDescription/modelDescription.xml` (GearPump) and
//! `modelDescription/TransmissionCircuit.xml` are the ones the variable
//! tables generate (the tables in `crates/fmu-models/src/fmi2/pump.rs` and
//! `crates/fmu-models/src/fmi2/circuit.rs` are the single sources of truth). After changing a
//! table, regenerate its file with
//!
//! ```text
//! cargo run -p fmu-build --release -- --model gear-pump --xml modelDescription/modelDescription.xml
//! cargo run -p fmu-build --release -- --model transmission-circuit --xml modelDescription/TransmissionCircuit.xml
//! ```
//!
//! (or run this test with `GEARPUMP_UPDATE_XML=1`), and change the GUID.

use std::path::Path;

use gearpump::fmi2::{model_description_xml, ExportedModel, FmuModel};

fn committed_matches_generated(model: FmuModel) {
    model.check().unwrap();
    let fresh = model.model_description_xml();
    let rel = model.committed_xml();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
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
             regenerate it: cargo run -p fmu-build --release -- --model {} --xml {rel}",
            path.display(),
            line + 1,
            committed.lines().nth(line).unwrap_or("<end of file>"),
            fresh.lines().nth(line).unwrap_or("<end of file>"),
            model.name(),
        );
    }
}

#[test]
fn committed_model_description_matches_the_variable_table() {
    assert_eq!(
        FmuModel::GearPump.model_description_xml(),
        model_description_xml::<ExportedModel>()
    );
    committed_matches_generated(FmuModel::GearPump);
}

#[test]
fn committed_circuit_model_description_matches_the_variable_table() {
    committed_matches_generated(FmuModel::TransmissionCircuit);
}

#[test]
fn model_description_has_the_fmu_contract() {
    // docs/interfaces.md section 7: names, causalities, units, display units.
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
        // every input and parameter with its physical range (issue 18
        // point 4: docs/interfaces.md section 7; crates/core/src/limits.rs in SI)
        r#"unit="rad/s" displayUnit="rpm" min="0" max="2094.3951023931954" start="104.71975511965977""#,
        r#"unit="Pa" displayUnit="bar" min="5000" max="5000000" start="101325""#,
        r#"unit="Pa" displayUnit="bar" min="5000" max="55000000" start="3101325""#,
        r#"unit="K" displayUnit="degC" min="253.15" max="423.15" start="333.15""#,
        r#"unit="m" displayUnit="um" min="1e-7" max="0.0005" start="0.00003""#,
        r#"unit="m" displayUnit="um" min="1e-7" max="0.0005" start="0.000012""#,
        r#"unit="m" displayUnit="um" min="1e-7" max="0.0005" start="0.000015""#,
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
