//! modelDescription.xml generation and the variable-table checks, on a
//! pump-like table (the units and display units of the FMU interface) and
//! on broken tables.

use std::path::Path;

use gearpump::fmi2::model::{Causality::*, Initial, Variability::*};
use gearpump::fmi2::{
    check_model, model_description_xml, CoSimModel, DefaultExperiment, ModelError, Variable,
};
use quick_xml::events::Event;
use quick_xml::Reader;

/// Implements the trait around a variable table (the behaviour is not used).
macro_rules! table_model {
    ($name:ident, $id:literal, $vars:expr) => {
        struct $name;
        impl CoSimModel for $name {
            const MODEL_IDENTIFIER: &'static str = $id;
            const GUID: &'static str = "{11111111-2222-3333-4444-555555555555}";
            const MODEL_NAME: &'static str = "test.PumpLike";
            const DESCRIPTION: &'static str = "a table <with> \"markup\" & such";
            const DEFAULT_EXPERIMENT: Option<DefaultExperiment> = Some(DefaultExperiment {
                start_time: 0.0,
                stop_time: 1.0,
                tolerance: Some(1e-6),
                step_size: 1e-4,
            });
            fn variables() -> &'static [Variable] {
                static V: &[Variable] = $vars;
                V
            }
            fn instantiate(_: &Path, _: &dyn Fn(&str)) -> Result<Self, ModelError> {
                Ok($name)
            }
            fn set_real(&mut self, _: u32, _: f64) -> Result<(), ModelError> {
                Ok(())
            }
            fn get_real(&self, _: u32) -> Result<f64, ModelError> {
                Ok(0.0)
            }
            fn exit_initialization(&mut self) -> Result<(), ModelError> {
                Ok(())
            }
            fn do_step(&mut self, _: f64, _: f64) -> Result<(), ModelError> {
                Ok(())
            }
            fn reset(&mut self) -> Result<(), ModelError> {
                Ok(())
            }
            fn save_state(&self) -> Vec<u8> {
                Vec::new()
            }
            fn restore_state(&mut self, _: &[u8]) -> Result<(), ModelError> {
                Ok(())
            }
        }
    };
}

table_model!(
    PumpLike,
    "PumpLike",
    &[
        Variable::real("speed", 1, Input, Continuous, "rad/s")
            .describe("driving shaft speed")
            .display("rpm")
            .start(104.719_755_119_659_77),
        Variable::real("p_in", 2, Input, Continuous, "Pa")
            .display("bar")
            .start(101_325.0),
        Variable::real("T_oil", 3, Input, Continuous, "K")
            .display("degC")
            .start(333.15),
        Variable::real("tip_clearance_drive", 4, Parameter, Fixed, "m")
            .display("um")
            .start(20e-6),
        Variable::boolean("micromotion", 5, Parameter, Fixed).start_bool(true),
        Variable::real("Q_out", 6, Output, Continuous, "m3/s").display("l/min"),
        Variable::real("torque", 7, Output, Continuous, "N.m")
            .initial(Initial::Approx)
            .start(0.0),
        Variable::real("V_delivered", 8, Output, Continuous, "m3")
            .initial(Initial::Exact)
            .start(0.0),
        Variable::real("eta_v", 9, Output, Continuous, "1"),
        Variable::boolean("cavitating", 10, Output, Discrete),
        Variable::real("theta", 11, Local, Continuous, "rad"),
    ]
);

/// (element name, attributes) of every start/empty element, in order.
fn elements(xml: &str) -> Vec<(String, Vec<(String, String)>)> {
    let mut r = Reader::from_str(xml);
    let mut out = Vec::new();
    loop {
        match r.read_event().unwrap() {
            Event::Start(e) | Event::Empty(e) => {
                let name = String::from_utf8(e.name().as_ref().to_vec()).unwrap();
                let attrs = e
                    .attributes()
                    .map(|a| {
                        let a = a.unwrap();
                        (
                            String::from_utf8(a.key.as_ref().to_vec()).unwrap(),
                            a.unescape_value().unwrap().into_owned(),
                        )
                    })
                    .collect();
                out.push((name, attrs));
            }
            Event::Eof => break,
            _ => {}
        }
    }
    out
}

fn attr<'a>(e: &'a (String, Vec<(String, String)>), key: &str) -> Option<&'a str> {
    e.1.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
}

#[test]
fn pump_like_table_is_valid() {
    check_model::<PumpLike>().unwrap();
}

#[test]
fn root_and_cosimulation_attributes() {
    let xml = model_description_xml::<PumpLike>();
    assert!(xml.starts_with("<?xml version=\"1.0\" encoding=\"UTF-8\"?>"));
    let el = elements(&xml);
    let root = &el[0];
    assert_eq!(root.0, "fmiModelDescription");
    assert_eq!(attr(root, "fmiVersion"), Some("2.0"));
    assert_eq!(attr(root, "guid"), Some(PumpLike::GUID));
    assert_eq!(attr(root, "description"), Some(PumpLike::DESCRIPTION));
    assert_eq!(attr(root, "variableNamingConvention"), Some("structured"));
    assert_eq!(attr(root, "numberOfEventIndicators"), Some("0"));
    assert!(attr(root, "generationTool")
        .unwrap()
        .starts_with("gearpump "));
    let cs = el.iter().find(|e| e.0 == "CoSimulation").unwrap();
    for (k, v) in [
        ("modelIdentifier", "PumpLike"),
        ("canHandleVariableCommunicationStepSize", "true"),
        ("canGetAndSetFMUstate", "true"),
        ("canSerializeFMUstate", "true"),
        ("canNotUseMemoryManagementFunctions", "true"),
        ("canBeInstantiatedOnlyOncePerProcess", "false"),
    ] {
        assert_eq!(attr(cs, k), Some(v), "{k}");
    }
    let de = el.iter().find(|e| e.0 == "DefaultExperiment").unwrap();
    assert_eq!(attr(de, "stepSize"), Some("0.0001"));
    assert_eq!(attr(de, "tolerance"), Some("1e-6"));
    // Deterministic: the same text every time.
    assert_eq!(xml, model_description_xml::<PumpLike>());
}

#[test]
fn elements_are_in_schema_order() {
    let xml = model_description_xml::<PumpLike>();
    let top: Vec<String> = elements(&xml)
        .into_iter()
        .map(|e| e.0)
        .filter(|n| {
            [
                "CoSimulation",
                "UnitDefinitions",
                "TypeDefinitions",
                "LogCategories",
                "DefaultExperiment",
                "ModelVariables",
                "ModelStructure",
            ]
            .contains(&n.as_str())
        })
        .collect();
    assert_eq!(
        top,
        [
            "CoSimulation",
            "UnitDefinitions",
            "LogCategories",
            "DefaultExperiment",
            "ModelVariables",
            "ModelStructure"
        ]
    );
}

#[test]
fn unit_definitions_have_si_exponents_and_display_units() {
    let xml = model_description_xml::<PumpLike>();
    let el = elements(&xml);
    let unit = |name: &str| {
        let i = el
            .iter()
            .position(|e| e.0 == "Unit" && attr(e, "name") == Some(name))
            .unwrap_or_else(|| panic!("unit {name} missing"));
        let base = &el[i + 1];
        assert_eq!(base.0, "BaseUnit");
        let displays: Vec<_> = el[i + 2..]
            .iter()
            .take_while(|e| e.0 == "DisplayUnit")
            .cloned()
            .collect();
        (base.clone(), displays)
    };
    let (b, d) = unit("rad/s");
    assert_eq!((attr(&b, "rad"), attr(&b, "s")), (Some("1"), Some("-1")));
    assert_eq!(attr(&d[0], "name"), Some("rpm"));
    let f: f64 = attr(&d[0], "factor").unwrap().parse().unwrap();
    assert!((f * 104.719_755_119_659_77 - 1000.0).abs() < 1e-9);
    let (b, d) = unit("Pa");
    assert_eq!(
        (attr(&b, "kg"), attr(&b, "m"), attr(&b, "s")),
        (Some("1"), Some("-1"), Some("-2"))
    );
    assert_eq!(
        (
            attr(&d[0], "name"),
            attr(&d[0], "factor"),
            attr(&d[0], "offset")
        ),
        (Some("bar"), Some("0.00001"), None)
    );
    let (b, d) = unit("K");
    assert_eq!(attr(&b, "K"), Some("1"));
    assert_eq!(
        (
            attr(&d[0], "name"),
            attr(&d[0], "factor"),
            attr(&d[0], "offset")
        ),
        (Some("degC"), None, Some("-273.15"))
    );
    let (b, d) = unit("m3/s");
    assert_eq!((attr(&b, "m"), attr(&b, "s")), (Some("3"), Some("-1")));
    assert_eq!(
        (attr(&d[0], "name"), attr(&d[0], "factor")),
        (Some("l/min"), Some("60000"))
    );
    let (b, _) = unit("N.m");
    assert_eq!(
        (attr(&b, "kg"), attr(&b, "m"), attr(&b, "s")),
        (Some("1"), Some("2"), Some("-2"))
    );
    let (b, _) = unit("1");
    assert!(b.1.is_empty());
    // Units no variable uses are not written.
    assert!(!el
        .iter()
        .any(|e| e.0 == "Unit" && attr(e, "name") == Some("Pa.s")));
}

#[test]
fn variables_and_model_structure() {
    let xml = model_description_xml::<PumpLike>();
    let el = elements(&xml);
    let vars: Vec<_> = el.iter().filter(|e| e.0 == "ScalarVariable").collect();
    assert_eq!(vars.len(), PumpLike::variables().len());
    let speed = vars[0];
    assert_eq!(attr(speed, "name"), Some("speed"));
    assert_eq!(attr(speed, "causality"), Some("input"));
    assert_eq!(attr(speed, "variability"), Some("continuous"));
    assert_eq!(attr(speed, "initial"), None);
    let real = el
        .iter()
        .find(|e| e.0 == "Real" && attr(e, "unit") == Some("rad/s"))
        .unwrap();
    assert_eq!(attr(real, "displayUnit"), Some("rpm"));
    assert_eq!(
        attr(real, "start").unwrap().parse::<f64>().unwrap(),
        104.719_755_119_659_77
    );
    let boolean = el.iter().find(|e| e.0 == "Boolean").unwrap();
    assert_eq!(attr(boolean, "start"), Some("true"));

    // Outputs: every output (indices 6..=10, 1-based); InitialUnknowns: the
    // outputs with initial calculated (default) or approx, not exact.
    let structure = el.iter().position(|e| e.0 == "ModelStructure").unwrap();
    let mut section = "";
    let mut outputs = Vec::new();
    let mut initial = Vec::new();
    for e in &el[structure + 1..] {
        match e.0.as_str() {
            "Outputs" | "InitialUnknowns" => section = if e.0 == "Outputs" { "o" } else { "i" },
            "Unknown" => {
                let i: usize = attr(e, "index").unwrap().parse().unwrap();
                if section == "o" {
                    &mut outputs
                } else {
                    &mut initial
                }
                .push(i);
            }
            _ => {}
        }
    }
    assert_eq!(outputs, [6, 7, 8, 9, 10]);
    assert_eq!(initial, [6, 7, 9, 10]);
}

#[test]
fn documentation_lists_every_variable_escaped() {
    let html = gearpump::fmi2::documentation_html::<PumpLike>();
    for v in PumpLike::variables() {
        assert!(
            html.contains(&format!("<code>{}</code>", v.name)),
            "{}",
            v.name
        );
    }
    assert!(html.contains("a table &lt;with&gt; &quot;markup&quot; &amp; such"));
    assert!(html.contains("rad/s (shown in rpm)"));
}

table_model!(
    Broken,
    "Broken-Id",
    &[
        Variable::real("u", 1, Input, Continuous, "m").initial(Initial::Exact),
        Variable::real("u", 2, Input, Continuous, "m"),
        Variable::real("p", 3, Parameter, Continuous, "m").start(1.0),
        Variable::real("q", 3, Parameter, Fixed, "furlong").start(1.0),
        Variable::real("y", 4, Output, Continuous, "m").start(1.0),
        Variable::real("z", 5, Output, Continuous, "m").display("bar"),
        Variable::real("w", 6, Parameter, Tunable, "m").start(f64::NAN),
        Variable::boolean("b", 7, Output, Continuous),
    ]
);

#[test]
fn check_model_reports_every_problem() {
    let problems = check_model::<Broken>().unwrap_err();
    let all = problems.join("\n");
    for needle in [
        "modelIdentifier \"Broken-Id\" is not a C identifier",
        "\"u\" (vr 1): initial=\"exact\" is not allowed for causality input",
        "\"u\" (vr 1): a start value is required",
        "\"u\" (vr 2): duplicate name",
        "\"p\" (vr 3): causality parameter with variability continuous is not allowed",
        "\"q\" (vr 3): value reference also used by \"p\"",
        "\"q\" (vr 3): unit \"furlong\" is not in the unit table",
        "\"y\" (vr 4): a start value is not allowed with initial=\"calculated\"",
        "\"z\" (vr 5): display unit \"bar\" is not defined for unit \"m\"",
        "\"w\" (vr 6): start value NaN is not finite",
        "\"b\" (vr 7): a Boolean cannot be continuous",
    ] {
        assert!(all.contains(needle), "missing {needle:?} in:\n{all}");
    }
    // The packager refuses such a model before writing anything.
    let out = std::env::temp_dir().join(format!("gearpump-broken-{}.fmu", std::process::id()));
    let err =
        gearpump::fmi2::build_model_fmu::<Broken>(&out, Path::new("/nonexistent.so")).unwrap_err();
    assert!(err.to_string().contains("variable table is invalid"));
    assert!(!out.exists());
}
