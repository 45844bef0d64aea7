//! Checks the XML written by `ModelDescription::to_xml`.

mod common;

use common::*;
use fmi2_model_description::*;
use quick_xml::events::Event;
use quick_xml::{Reader, XmlVersion};

/// Byte position of `needle`, panicking with the document when absent.
fn pos(xml: &str, needle: &str) -> usize {
    xml.find(needle)
        .unwrap_or_else(|| panic!("{needle:?} not found in:\n{xml}"))
}

/// The value of attribute `attr` in the first tag that contains `anchor`.
fn attr_after<'a>(xml: &'a str, anchor: &str, attr: &str) -> &'a str {
    let start = pos(xml, anchor);
    let tag_end = start + xml[start..].find('>').unwrap();
    let tag = &xml[start..tag_end];
    let key = format!(" {attr}=\"");
    let v = tag
        .find(&key)
        .unwrap_or_else(|| panic!("{attr} missing in {tag}"))
        + key.len();
    let len = tag[v..].find('"').unwrap();
    &xml[start + v..start + v + len]
}

/// Parses the document; returns element names in document order.
fn parse(xml: &str) -> Vec<String> {
    let mut reader = Reader::from_str(xml);
    let mut names = Vec::new();
    loop {
        match reader.read_event().expect("well-formed XML") {
            Event::Start(e) | Event::Empty(e) => {
                for a in e.attributes() {
                    a.expect("valid attribute")
                        .normalized_value(XmlVersion::Implicit1_0)
                        .expect("valid escape");
                }
                names.push(e.name().as_ref().to_string());
            }
            Event::Eof => break,
            _ => {}
        }
    }
    names
}

#[test]
fn header_and_root_attributes() {
    let xml = sample().to_xml().unwrap();
    assert!(xml.starts_with("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<fmiModelDescription "));
    let root = &xml[..pos(&xml, "<CoSimulation")];
    let order = [
        "fmiVersion=\"2.0\"",
        "modelName=\"Tensegrity\"",
        "guid=\"{8c4e810f-3df3-4a00-8276-176fa3c9f000}\"",
        "description=",
        "author=\"A. Author\"",
        "version=\"1.2.3\"",
        "copyright=\"© 2026 A. Author\"",
        "license=\"MIT OR Apache-2.0\"",
        "generationTool=\"fmi2-model-description\"",
        "generationDateAndTime=\"2024-01-01T00:00:00Z\"",
        "variableNamingConvention=\"structured\"",
        "numberOfEventIndicators=\"0\"",
    ];
    let p: Vec<usize> = order.iter().map(|a| pos(root, a)).collect();
    assert!(p.windows(2).all(|w| w[0] < w[1]), "{root}");
    // Pretty-printed.
    assert!(xml.contains("\n  <CoSimulation"));
    assert!(xml.contains("\n    <ScalarVariable"));
}

#[test]
fn element_order_and_well_formed() {
    let xml = sample().to_xml().unwrap();
    let names = parse(&xml);
    let top = [
        "CoSimulation",
        "UnitDefinitions",
        "TypeDefinitions",
        "LogCategories",
        "DefaultExperiment",
        "ModelVariables",
        "ModelStructure",
    ];
    let p: Vec<usize> = top
        .iter()
        .map(|t| names.iter().position(|n| n == t).unwrap())
        .collect();
    assert!(p.windows(2).all(|w| w[0] < w[1]), "{names:?}");
    assert_eq!(names[0], "fmiModelDescription");
    let n_vars = names.iter().filter(|n| *n == "ScalarVariable").count();
    assert_eq!(n_vars, sample().model_variables.len());
    // ModelStructure: Outputs before InitialUnknowns; empty Derivatives omitted.
    let ms = &xml[pos(&xml, "<ModelStructure>")..];
    assert!(pos(ms, "<Outputs>") < pos(ms, "<InitialUnknowns>"));
    assert!(!xml.contains("Derivatives"));
    assert!(xml.trim_end().ends_with("</fmiModelDescription>"));
}

#[test]
fn co_simulation_attributes() {
    let xml = sample().to_xml().unwrap();
    let cs = "<CoSimulation";
    assert_eq!(attr_after(&xml, cs, "modelIdentifier"), "tensegrity");
    let t = "canHandleVariableCommunicationStepSize";
    assert_eq!(attr_after(&xml, cs, t), "true");
    assert_eq!(attr_after(&xml, cs, "canGetAndSetFMUstate"), "true");
    assert_eq!(attr_after(&xml, cs, "canSerializeFMUstate"), "true");
    let t = "canNotUseMemoryManagementFunctions";
    assert_eq!(attr_after(&xml, cs, t), "true");
    let t = "canBeInstantiatedOnlyOncePerProcess";
    assert_eq!(attr_after(&xml, cs, t), "false");
    assert_eq!(
        attr_after(&xml, cs, "providesDirectionalDerivative"),
        "false"
    );
    assert_eq!(attr_after(&xml, cs, "canInterpolateInputs"), "false");
    assert_eq!(attr_after(&xml, cs, "maxOutputDerivativeOrder"), "0");
}

#[test]
fn units_types_categories_experiment() {
    let xml = sample().to_xml().unwrap();
    assert!(xml.contains("<Unit name=\"m\">\n      <BaseUnit m=\"1\"/>\n    </Unit>"));
    assert!(xml.contains("<BaseUnit kg=\"1\" m=\"1\" s=\"-2\"/>"));
    assert!(xml.contains("<BaseUnit K=\"1\" offset=\"273.15\"/>"));
    let f = attr_after(&xml, "<BaseUnit rad=", "factor");
    assert_eq!(f.parse::<f64>().unwrap(), std::f64::consts::PI / 180.0);
    assert!(xml.contains("<SimpleType name=\"Solver\" description=\"integration &amp; projection\">\n      <Enumeration>\n        <Item name=\"euler\" value=\"1\" description=\"explicit\"/>\n        <Item name=\"rk4\" value=\"2\"/>\n      </Enumeration>"));
    assert!(xml.contains("<Category name=\"logStatusError\" description=\"errors\"/>"));
    assert!(xml.contains("<Category name=\"logAll\"/>"));
    assert!(xml.contains("<DefaultExperiment startTime=\"0\" stopTime=\"10\" stepSize=\"0.001\"/>"));
}

#[test]
fn variables() {
    let xml = sample().to_xml().unwrap();
    assert!(xml.contains(
        "<ScalarVariable name=\"force\" valueReference=\"1\" causality=\"input\" variability=\"continuous\">\n      <Real unit=\"N\" start=\"0\"/>\n    </ScalarVariable>"
    ));
    assert!(xml.contains("<ScalarVariable name=\"steps\" valueReference=\"2\" causality=\"output\" variability=\"discrete\" initial=\"calculated\">\n      <Integer min=\"0\"/>"));
    assert!(xml.contains("<Integer start=\"-7\" min=\"-10\" max=\"10\"/>"));
    assert!(xml.contains("<Boolean start=\"true\"/>"));
    assert!(xml.contains("<Boolean start=\"false\"/>"));
    assert!(xml.contains("<Enumeration declaredType=\"Solver\" start=\"2\"/>"));
    assert!(xml.contains("causality=\"calculatedParameter\" variability=\"fixed\" initial=\"calculated\">\n      <Enumeration declaredType=\"Solver\"/>"));
    assert!(xml.contains("<String start=\"constant\"/>"));
    assert!(xml.contains("causality=\"local\" variability=\"constant\">"));
    assert!(xml.contains(
        "causality=\"independent\" variability=\"continuous\">\n      <Real unit=\"s\"/>"
    ));
    assert!(xml.contains("variability=\"tunable\" initial=\"exact\">"));
    let x = "name=\"node[1].x\"";
    assert_eq!(attr_after(&xml, x, "valueReference"), "0");
    let real = &xml[pos(&xml, x)..];
    assert_eq!(attr_after(real, "<Real", "unit"), "m");
    assert_eq!(attr_after(real, "<Real", "max"), "1");
}

#[test]
fn model_structure() {
    let xml = sample().to_xml().unwrap();
    assert!(xml.contains(
        "<Outputs>\n      <Unknown index=\"1\" dependencies=\"2 11\" dependenciesKind=\"dependent constant\"/>\n      <Unknown index=\"3\" dependencies=\"\"/>\n    </Outputs>"
    ));
    assert!(xml.contains(
        "<InitialUnknowns>\n      <Unknown index=\"3\"/>\n      <Unknown index=\"8\"/>\n    </InitialUnknowns>"
    ));
}

#[test]
fn empty_lists_are_omitted() {
    let xml = minimal().to_xml().unwrap();
    parse(&xml);
    for tag in [
        "UnitDefinitions",
        "TypeDefinitions",
        "LogCategories",
        "DefaultExperiment",
        "Outputs",
        "Derivatives",
        "InitialUnknowns",
        "description=",
        "author",
        "\" version=",
        "copyright",
        "license",
        "generationTool",
        "generationDateAndTime",
    ] {
        assert!(!xml.contains(tag), "{tag} in\n{xml}");
    }
    assert!(xml.contains("<ModelVariables/>"), "{xml}");
    assert!(xml.contains("<ModelStructure/>"), "{xml}");
    assert!(pos(&xml, "<CoSimulation") < pos(&xml, "<ModelVariables/>"));

    let mut md = minimal();
    md.model_structure.derivatives = vec![Unknown {
        index: 1,
        ..Default::default()
    }];
    let xml = md.to_xml().unwrap();
    assert!(xml.contains("<ModelStructure>\n    <Derivatives>\n      <Unknown index=\"1\"/>"));
    assert!(!xml.contains("Outputs") && !xml.contains("InitialUnknowns"));
}

#[test]
fn reals_round_trip_bit_exactly() {
    let xml = sample().to_xml().unwrap();
    for (i, &x) in REALS.iter().enumerate() {
        let anchor = format!("name=\"rt{i}\"");
        let var = &xml[pos(&xml, &anchor)..];
        let text = attr_after(var, "<Real", "start");
        let y: f64 = text.parse().unwrap();
        assert_eq!(x.to_bits(), y.to_bits(), "{x:?} written as {text}");
        assert!(text.len() <= 24, "{x:?} written as long {text}");
    }
    let x = "name=\"node[1].x\"";
    let var = &xml[pos(&xml, x)..];
    let start: f64 = attr_after(var, "<Real", "start").parse().unwrap();
    let min: f64 = attr_after(var, "<Real", "min").parse().unwrap();
    assert_eq!(start.to_bits(), 0.5773502691896258f64.to_bits());
    assert_eq!(min.to_bits(), (-1.0605752387249069e-16f64).to_bits());
}

#[test]
fn non_finite_reals_are_errors() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut md = minimal();
        md.model_variables.push(real("x", 0, Some(bad)));
        assert!(md.to_xml().is_err());
        let mut md = minimal();
        md.default_experiment = Some(DefaultExperiment {
            stop_time: Some(bad),
            ..Default::default()
        });
        let err = md.to_xml().unwrap_err();
        assert!(err.to_string().contains("non-finite"), "{err}");
        let mut md = minimal();
        md.unit_definitions.push(Unit {
            name: "u".into(),
            base_unit: BaseUnit {
                factor: bad,
                ..Default::default()
            },
        });
        assert!(md.to_xml().is_err());
    }
}

#[test]
fn text_is_escaped() {
    let xml = sample().to_xml().unwrap();
    let escaped = "a &lt; b &amp; &quot;c&quot; 'd' &gt; e: ‖b‖ − l";
    assert!(xml.contains(&format!("description=\"{escaped}\"")), "{xml}");
    assert!(xml.contains(&format!("<String start=\"{escaped}\"/>")));
    assert!(!xml.contains("a < b"));
    // Unescapes back to the original in every place it was written.
    let mut reader = Reader::from_str(&xml);
    let mut found = Vec::new();
    loop {
        match reader.read_event().unwrap() {
            Event::Start(e) | Event::Empty(e) => {
                for a in e.attributes() {
                    let v = a
                        .unwrap()
                        .normalized_value(XmlVersion::Implicit1_0)
                        .unwrap();
                    if v.contains('‖') {
                        found.push(v.into_owned());
                    }
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    // Root description, variable description, String start.
    assert_eq!(found, [TRICKY; 3]);
}
