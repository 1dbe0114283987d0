//! `modelDescription.xml` and `documentation/index.html`, generated from a
//! model's variable table ([`CoSimModel::variables`]) and constants.
//!
//! Elements are written in the order of the FMI 2.0 schema
//! (`fmiModelDescription`: CoSimulation, UnitDefinitions, LogCategories,
//! DefaultExperiment, ModelVariables, ModelStructure). `ModelStructure/Outputs`
//! lists every output; `InitialUnknowns` lists the outputs whose `initial` is
//! calculated or approx, by 1-based index into `ModelVariables`. Output is
//! deterministic (no generation date), so a committed copy can be compared
//! with a fresh one.

use std::io;

use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, BytesText, Event};
use quick_xml::Writer;

use super::instance::LOG_CATEGORIES;
use super::model::{Causality, CoSimModel, Initial, UnitDefinition, Variable, VariableKind};

/// The `generationTool` attribute.
pub fn generation_tool() -> String {
    format!("gearpump {} (fmi2 module)", env!("CARGO_PKG_VERSION"))
}

/// A Real as an `xs:double` that reads back to the same value.
pub fn fmt_f64(x: f64) -> String {
    let a = x.abs();
    if a != 0.0 && !(1e-5..1e15).contains(&a) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

fn bool_str(b: bool) -> &'static str {
    if b {
        "true"
    } else {
        "false"
    }
}

/// The units of `units` that the model's variables use, in table order.
pub fn used_units<M: CoSimModel>() -> Vec<&'static UnitDefinition> {
    used_units_of::<M>(M::variables())
}

fn used_units_of<M: CoSimModel>(vars: &[Variable]) -> Vec<&'static UnitDefinition> {
    M::units()
        .iter()
        .filter(|u| {
            vars.iter()
                .any(|v| matches!(v.kind, VariableKind::Real { unit: Some(n), .. } if n == u.name))
        })
        .collect()
}

/// Indices (1-based) of the outputs, and of the outputs that are initial
/// unknowns.
pub fn model_structure<M: CoSimModel>() -> (Vec<usize>, Vec<usize>) {
    model_structure_of(M::variables())
}

fn model_structure_of(vars: &[Variable]) -> (Vec<usize>, Vec<usize>) {
    let mut outputs = Vec::new();
    let mut initial = Vec::new();
    for (i, v) in vars.iter().enumerate() {
        if v.causality == Causality::Output {
            outputs.push(i + 1);
            if matches!(
                v.effective_initial(),
                Some(Initial::Calculated | Initial::Approx)
            ) {
                initial.push(i + 1);
            }
        }
    }
    (outputs, initial)
}

/// The `modelDescription.xml` of model `M` (UTF-8, 2-space indented).
/// Run [`super::model::check_model`] first: this function writes the table
/// as it is.
pub fn model_description_xml<M: CoSimModel>() -> String {
    model_description_xml_with::<M>(M::variables())
}

/// [`model_description_xml`] with `vars` in place of the model's table: the
/// same variables (names, references, causalities, units) with other start
/// values or ranges, e.g. those of the design an FMU is built for.
pub fn model_description_xml_with<M: CoSimModel>(vars: &[Variable]) -> String {
    model_description_xml_for::<M>(vars, M::GUID)
}

/// [`model_description_xml_with`] under `guid` (an FMU whose resources
/// differ from the model's own: see `CoSimModel::guid_for_resources`).
pub fn model_description_xml_for<M: CoSimModel>(vars: &[Variable], guid: &str) -> String {
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    // Writing into a Vec cannot fail.
    write_model_description::<M>(&mut w, vars, guid).expect("writing XML into memory");
    let mut s = String::from_utf8(w.into_inner()).expect("quick-xml writes UTF-8");
    s.push('\n');
    s
}

type W = Writer<Vec<u8>>;

fn start(w: &mut W, name: &str, attrs: &[(&str, &str)]) -> io::Result<()> {
    let mut e = BytesStart::new(name);
    for a in attrs {
        e.push_attribute(*a);
    }
    w.write_event(Event::Start(e))
}

fn empty(w: &mut W, name: &str, attrs: &[(&str, &str)]) -> io::Result<()> {
    let mut e = BytesStart::new(name);
    for a in attrs {
        e.push_attribute(*a);
    }
    w.write_event(Event::Empty(e))
}

fn end(w: &mut W, name: &str) -> io::Result<()> {
    w.write_event(Event::End(BytesEnd::new(name)))
}

fn write_model_description<M: CoSimModel>(
    w: &mut W,
    vars: &[Variable],
    guid: &str,
) -> io::Result<()> {
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
    let tool = generation_tool();
    let mut root = vec![
        ("fmiVersion", "2.0"),
        ("modelName", M::MODEL_NAME),
        ("guid", guid),
    ];
    if !M::DESCRIPTION.is_empty() {
        root.push(("description", M::DESCRIPTION));
    }
    if !M::AUTHOR.is_empty() {
        root.push(("author", M::AUTHOR));
    }
    if !M::VERSION.is_empty() {
        root.push(("version", M::VERSION));
    }
    root.extend([
        ("generationTool", tool.as_str()),
        ("variableNamingConvention", "structured"),
        ("numberOfEventIndicators", "0"),
    ]);
    start(w, "fmiModelDescription", &root)?;

    empty(
        w,
        "CoSimulation",
        &[
            ("modelIdentifier", M::MODEL_IDENTIFIER),
            ("needsExecutionTool", "false"),
            ("canHandleVariableCommunicationStepSize", "true"),
            ("canInterpolateInputs", "false"),
            ("maxOutputDerivativeOrder", "0"),
            ("canRunAsynchronuously", "false"),
            ("canBeInstantiatedOnlyOncePerProcess", "false"),
            ("canNotUseMemoryManagementFunctions", "true"),
            ("canGetAndSetFMUstate", "true"),
            ("canSerializeFMUstate", "true"),
            (
                "providesDirectionalDerivative",
                bool_str(M::PROVIDES_DIRECTIONAL_DERIVATIVE),
            ),
        ],
    )?;

    let units = used_units_of::<M>(vars);
    if !units.is_empty() {
        start(w, "UnitDefinitions", &[])?;
        for u in units {
            start(w, "Unit", &[("name", u.name)])?;
            let b = u.base;
            let exps: Vec<(&str, String)> = [
                ("kg", b.kg),
                ("m", b.m),
                ("s", b.s),
                ("A", b.a),
                ("K", b.k),
                ("mol", b.mol),
                ("cd", b.cd),
                ("rad", b.rad),
            ]
            .into_iter()
            .filter(|(_, e)| *e != 0)
            .map(|(n, e)| (n, e.to_string()))
            .collect();
            let attrs: Vec<(&str, &str)> = exps.iter().map(|(n, e)| (*n, e.as_str())).collect();
            empty(w, "BaseUnit", &attrs)?;
            for d in u.display {
                let factor = fmt_f64(d.factor);
                let offset = fmt_f64(d.offset);
                let mut attrs = vec![("name", d.name)];
                if d.factor != 1.0 {
                    attrs.push(("factor", factor.as_str()));
                }
                if d.offset != 0.0 {
                    attrs.push(("offset", offset.as_str()));
                }
                empty(w, "DisplayUnit", &attrs)?;
            }
            end(w, "Unit")?;
        }
        end(w, "UnitDefinitions")?;
    }

    start(w, "LogCategories", &[])?;
    for (name, description) in LOG_CATEGORIES {
        empty(
            w,
            "Category",
            &[("name", name), ("description", description)],
        )?;
    }
    end(w, "LogCategories")?;

    if let Some(e) = M::DEFAULT_EXPERIMENT {
        let (s, t, h) = (
            fmt_f64(e.start_time),
            fmt_f64(e.stop_time),
            fmt_f64(e.step_size),
        );
        let tol = e.tolerance.map(fmt_f64);
        let mut attrs = vec![("startTime", s.as_str()), ("stopTime", t.as_str())];
        if let Some(tol) = &tol {
            attrs.push(("tolerance", tol.as_str()));
        }
        attrs.push(("stepSize", h.as_str()));
        empty(w, "DefaultExperiment", &attrs)?;
    }

    start(w, "ModelVariables", &[])?;
    for (i, v) in vars.iter().enumerate() {
        w.write_event(Event::Comment(BytesText::new(&format!(
            " index {} ",
            i + 1
        ))))?;
        let vr = v.value_reference.to_string();
        let mut attrs = vec![("name", v.name), ("valueReference", vr.as_str())];
        if !v.description.is_empty() {
            attrs.push(("description", v.description));
        }
        attrs.push(("causality", v.causality.as_str()));
        attrs.push(("variability", v.variability.as_str()));
        if let Some(init) = v.initial {
            attrs.push(("initial", init.as_str()));
        }
        start(w, "ScalarVariable", &attrs)?;
        match v.kind {
            VariableKind::Real {
                unit,
                display_unit,
                start: s,
                min,
                max,
            } => {
                let s = s.map(fmt_f64);
                let (min, max) = (min.map(fmt_f64), max.map(fmt_f64));
                let mut attrs = Vec::new();
                if let Some(u) = unit {
                    attrs.push(("unit", u));
                }
                if let Some(d) = display_unit {
                    attrs.push(("displayUnit", d));
                }
                if let Some(x) = &min {
                    attrs.push(("min", x.as_str()));
                }
                if let Some(x) = &max {
                    attrs.push(("max", x.as_str()));
                }
                if let Some(s) = &s {
                    attrs.push(("start", s.as_str()));
                }
                empty(w, "Real", &attrs)?;
            }
            VariableKind::Boolean { start: s } => {
                let attrs: Vec<(&str, &str)> =
                    s.map(|b| ("start", bool_str(b))).into_iter().collect();
                empty(w, "Boolean", &attrs)?;
            }
            VariableKind::Integer { start, min, max } => {
                let text = [("min", min), ("max", max), ("start", start)]
                    .into_iter()
                    .filter_map(|(k, x)| x.map(|x| (k, x.to_string())))
                    .collect::<Vec<_>>();
                let attrs: Vec<(&str, &str)> = text.iter().map(|(k, x)| (*k, x.as_str())).collect();
                empty(w, "Integer", &attrs)?;
            }
        }
        end(w, "ScalarVariable")?;
    }
    end(w, "ModelVariables")?;

    let (outputs, initial) = model_structure_of(vars);
    start(w, "ModelStructure", &[])?;
    for (name, list) in [("Outputs", &outputs), ("InitialUnknowns", &initial)] {
        if list.is_empty() {
            continue;
        }
        start(w, name, &[])?;
        for &i in list {
            let index = i.to_string();
            let mut attrs = vec![("index", index.as_str())];
            // the declared dependencies of an output on the inputs (in
            // Outputs only: an initial unknown may also depend on parameters)
            let deps = (name == "Outputs")
                .then(|| M::output_dependencies(vars[i - 1].value_reference))
                .flatten()
                .map(|d| {
                    let idx: Vec<String> = d
                        .iter()
                        .filter_map(|r| {
                            vars.iter()
                                .position(|v| {
                                    v.value_reference == *r && v.causality == Causality::Input
                                })
                                .map(|p| (p + 1).to_string())
                        })
                        .collect();
                    let kinds = vec!["dependent"; idx.len()];
                    (idx.join(" "), kinds.join(" "))
                });
            if let Some((d, k)) = &deps {
                attrs.push(("dependencies", d.as_str()));
                attrs.push(("dependenciesKind", k.as_str()));
            }
            empty(w, "Unknown", &attrs)?;
        }
        end(w, name)?;
    }
    end(w, "ModelStructure")?;

    end(w, "fmiModelDescription")
}

fn html_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            _ => out.push(c),
        }
    }
    out
}

/// `documentation/index.html`: the model's description, its variable
/// table (units, display units, start values) and the FMU's capabilities.
pub fn documentation_html<M: CoSimModel>() -> String {
    documentation_html_with::<M>(M::variables())
}

/// [`documentation_html`] with `vars` in place of the model's table (see
/// [`model_description_xml_with`]).
pub fn documentation_html_with<M: CoSimModel>(vars: &[Variable]) -> String {
    documentation_html_for::<M>(vars, M::GUID)
}

/// [`documentation_html_with`] under `guid` (see
/// [`model_description_xml_for`]).
pub fn documentation_html_for<M: CoSimModel>(vars: &[Variable], guid: &str) -> String {
    let mut rows = String::new();
    for v in vars {
        let (ty, unit, start) = match v.kind {
            VariableKind::Real {
                unit,
                display_unit,
                start,
                min,
                max,
            } => {
                let mut unit = match (unit, display_unit) {
                    (Some(u), Some(d)) => format!("{u} (shown in {d})"),
                    (Some(u), None) => u.to_string(),
                    _ => String::new(),
                };
                if let (Some(lo), Some(hi)) = (min, max) {
                    unit.push_str(&format!(", within [{}, {}]", fmt_f64(lo), fmt_f64(hi)));
                }
                ("Real", unit, start.map(fmt_f64).unwrap_or_default())
            }
            VariableKind::Boolean { start } => (
                "Boolean",
                String::new(),
                start.map(|b| bool_str(b).to_string()).unwrap_or_default(),
            ),
            VariableKind::Integer { start, min, max } => (
                "Integer",
                match (min, max) {
                    (Some(lo), Some(hi)) => format!("within [{lo}, {hi}]"),
                    _ => String::new(),
                },
                start.map(|x| x.to_string()).unwrap_or_default(),
            ),
        };
        rows.push_str(&format!(
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            html_escape(v.name),
            v.value_reference,
            v.causality.as_str(),
            v.variability.as_str(),
            ty,
            html_escape(&unit),
            html_escape(&start),
            html_escape(v.description)
        ));
    }
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head><meta charset=\"utf-8\"><title>{name}</title>\n\
<style>body{{font-family:sans-serif;max-width:60em;margin:2em auto}}table{{border-collapse:collapse}}\
td,th{{border:1px solid #ccc;padding:.2em .5em;text-align:left}}</style></head>\n<body>\n\
<h1>{name}</h1>\n<p>{description}</p>\n\
<p>FMI 2.0 co-simulation FMU, model identifier <code>{id}</code>, GUID <code>{guid}</code>, \
generated by {tool}. All variables are in SI units; display units are given for tools \
that show them.</p>\n\
<h2>Variables</h2>\n<table>\n<tr><th>name</th><th>vr</th><th>causality</th><th>variability</th>\
<th>type</th><th>unit</th><th>start</th><th>description</th></tr>\n{rows}</table>\n\
<h2>Capabilities and behaviour</h2>\n<ul>\n\
<li>Variable communication step size; several instances per process and on several threads.</li>\n\
<li>FMU state get/set and serialization (the serialized bytes restore in another process).</li>\n\
<li>An invalid value (NaN, out of range) given to <code>fmi2SetReal</code>, or a step that \
cannot be computed, returns <code>fmi2Error</code> with a message through the logger; the \
instance can then be rolled back with <code>fmi2SetFMUstate</code>, reset or freed.</li>\n\
<li><code>fmi2DoStep</code> requires contiguous steps (currentCommunicationPoint equal to the end \
of the previous step, relative tolerance 1e-8) and a step size &gt; 0.</li>\n\
<li>{directional}</li>\n\
</ul>\n{model_doc}</body>\n</html>\n",
        name = html_escape(M::MODEL_NAME),
        description = html_escape(M::DESCRIPTION),
        id = html_escape(M::MODEL_IDENTIFIER),
        guid = html_escape(guid),
        tool = html_escape(&generation_tool()),
        model_doc = M::documentation(),
        directional = if M::PROVIDES_DIRECTIONAL_DERIVATIVE {
            "Directional derivatives of the outputs whose ModelStructure entry lists dependencies, \
             with respect to those inputs. Not supported: model exchange, input derivatives, \
             asynchronous steps."
        } else {
            "Not supported: model exchange, directional derivatives, input derivatives, \
             asynchronous steps."
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn doubles_read_back() {
        for x in [
            0.0,
            1.0,
            -2.5,
            1e-5,
            3.101325e6,
            1e-12,
            9.54929658551372,
            1e300,
            -273.15,
        ] {
            let s = fmt_f64(x);
            assert_eq!(s.parse::<f64>().unwrap(), x, "{s}");
        }
        assert_eq!(fmt_f64(1e-12), "1e-12");
        assert_eq!(fmt_f64(101325.0), "101325");
    }
}
