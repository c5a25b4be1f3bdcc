//! The tolerant first pass over URDF text, before urdf-rs's strict parser:
//! what the simulators researchers use (MuJoCo's and Isaac Gym's URDF import)
//! accept, quadcl accepts too, with a warning.
//!
//! - An element the URDF format allows once (a visual's `<material>`, a
//!   joint's `<limit>`, an inertial's `<mass>`) that appears again: repeats
//!   that are copies of the first are dropped; differing repeats are dropped
//!   too where they cannot change the dynamics (inside `<visual>`), and are an
//!   error everywhere else (two different masses have no right answer).
//! - Elements the format does not know inside `<robot>`, `<link>` and
//!   `<joint>` are dropped (the ROS extensions `<gazebo>`, `<transmission>` and
//!   `<ros2_control>` silently, anything else with a warning). What those
//!   extensions hold is never read: a `<joint>` a transmission names is not a
//!   joint, a `<link>` inside a Gazebo plugin is not a link, and their numbers
//!   and xacro leftovers are not checked (ROS's parser and MuJoCo's importer
//!   skip them the same way).
//! - A number that does not parse is an error naming its line and attribute;
//!   a xacro expression (`$(arg X)`, `${...}`) is one too, saying the file needs
//!   `xacro` first. Comments, processing instructions and CDATA are not markup:
//!   what they hold is never read as a number (ROS's parser and MuJoCo's importer
//!   skip them too), and a UTF-8 byte-order mark is dropped.
//!
//! Returns the cleaned text, which urdf-rs then reads.

use anyhow::{anyhow, bail};
use xml::{Element, Xml};

/// Children `<robot>` may have; the [`ROS_EXTENSIONS`] are dropped silently.
const ROBOT_CHILDREN: [&str; 6] = ["link", "joint", "material", "gazebo", "transmission", "ros2_control"];
/// ROS's extensions to URDF, for other tools (Gazebo, ros_control): dropped wherever they are, unread.
const ROS_EXTENSIONS: [&str; 3] = ["gazebo", "transmission", "ros2_control"];
/// Children a `<link>` may have (any number of visuals and collisions).
const LINK_CHILDREN: [&str; 3] = ["inertial", "visual", "collision"];
/// Children a `<joint>` may have, each at most once.
const JOINT_CHILDREN: [&str; 9] =
    ["origin", "parent", "child", "axis", "calibration", "dynamics", "limit", "mimic", "safety_controller"];

/// Attributes whose value is one or more numbers.
const NUMERIC_ATTRIBUTES: [&str; 17] = [
    "value", "xyz", "rpy", "ixx", "ixy", "ixz", "iyy", "iyz", "izz", "lower", "upper", "effort", "velocity", "radius",
    "length", "size", "scale",
];

/// Cleans URDF text; pushes one line per tolerated problem onto `warnings`.
pub(super) fn tolerant_urdf_text(text: &str, warnings: &mut Vec<String>) -> anyhow::Result<String> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if let Some(bad) = find_bad_number(&blank_elements(&blank_non_markup(text), &ROS_EXTENSIONS)) {
        bail!("bad number: {bad}");
    }
    let mut robot: Element = text.parse().map_err(|e| anyhow!("malformed URDF: {e}"))?;
    if robot.name != "robot" {
        bail!("malformed URDF: the root element is <{}>, expected <robot>", robot.name);
    }
    keep_known(&mut robot, "robot", &ROBOT_CHILDREN, warnings);
    robot.children.retain(|c| !matches!(c, Xml::ElementNode(e) if ROS_EXTENSIONS.contains(&e.name.as_str())));
    for child in elements_mut(&mut robot) {
        let owner = format!("{} '{}'", child.name, child.get_attribute("name", None).unwrap_or("?"));
        match child.name.as_str() {
            "link" => {
                keep_known(child, &owner, &LINK_CHILDREN, warnings);
                once_each(child, &owner, &["inertial"], true, warnings)?;
                for part in elements_mut(child) {
                    let (what, dynamic, singles): (_, _, &[&str]) = match part.name.as_str() {
                        "inertial" => ("<inertial>", true, &["origin", "mass", "inertia"]),
                        "collision" => ("<collision>", true, &["origin", "geometry"]),
                        _ => ("<visual>", false, &["origin", "geometry", "material"]),
                    };
                    once_each(part, &format!("{owner} {what}"), singles, dynamic, warnings)?;
                }
            }
            "joint" => {
                keep_known(child, &owner, &JOINT_CHILDREN, warnings);
                once_each(child, &owner, &JOINT_CHILDREN, true, warnings)?;
            }
            _ => {}
        }
    }
    Ok(robot.to_string())
}

fn elements_mut(e: &mut Element) -> impl Iterator<Item = &mut Element> {
    e.children.iter_mut().filter_map(|c| match c {
        Xml::ElementNode(e) => Some(e),
        _ => None,
    })
}

/// Drops the children of `e` whose name is not in `known`, with a warning each (ROS extensions
/// without one).
fn keep_known(e: &mut Element, owner: &str, known: &[&str], warnings: &mut Vec<String>) {
    e.children.retain(|c| match c {
        Xml::ElementNode(child) if !known.contains(&child.name.as_str()) => {
            if !ROS_EXTENSIONS.contains(&child.name.as_str()) {
                warnings.push(format!("{owner}: unknown element <{}> ignored", child.name));
            }
            false
        }
        _ => true,
    });
}

/// Keeps the first of each repeated `singles` child of `e`. A repeat that is a
/// copy of the first is dropped with a warning; a differing one too when
/// `dynamic` is false, else it is an error.
fn once_each(
    e: &mut Element,
    owner: &str,
    singles: &[&str],
    dynamic: bool,
    warnings: &mut Vec<String>,
) -> anyhow::Result<()> {
    for &name in singles {
        let mut first: Option<Element> = None;
        let mut error = None;
        e.children.retain(|c| {
            let Xml::ElementNode(child) = c else { return true };
            if child.name != name {
                return true;
            }
            match &first {
                None => {
                    first = Some(child.clone());
                    true
                }
                Some(kept) if same(kept, child) => {
                    warnings.push(format!("{owner}: repeated <{name}> (a copy of the first) ignored"));
                    false
                }
                Some(_) if !dynamic => {
                    warnings.push(format!("{owner}: repeated <{name}> differs from the first; the first is used"));
                    false
                }
                Some(_) => {
                    error.get_or_insert_with(|| {
                        anyhow!("{owner} has two different <{name}> elements (the URDF format allows one)")
                    });
                    true
                }
            }
        });
        if let Some(error) = error {
            return Err(error);
        }
    }
    Ok(())
}

/// Whether two elements say the same: name, attributes and child elements,
/// whatever the whitespace between them.
fn same(a: &Element, b: &Element) -> bool {
    let kids = |e: &Element| -> Vec<Element> {
        e.children
            .iter()
            .filter_map(|c| match c {
                Xml::ElementNode(e) => Some(e.clone()),
                _ => None,
            })
            .collect()
    };
    let (ka, kb) = (kids(a), kids(b));
    a.name == b.name
        && a.attributes == b.attributes
        && ka.len() == kb.len()
        && ka.iter().zip(&kb).all(|(x, y)| same(x, y))
}

/// `text` with every comment, processing instruction and CDATA section blanked out (each of
/// their characters but line breaks replaced by a space), so lines keep their numbers.
fn blank_non_markup(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some((at, end)) = ["<!--", "<?", "<![CDATA["]
        .iter()
        .zip(["-->", "?>", "]]>"])
        .filter_map(|(open, close)| rest.find(open).map(|at| (at, close)))
        .min_by_key(|(at, _)| *at)
    {
        out.push_str(&rest[..at]);
        let span_end = rest[at..].find(end).map_or(rest.len(), |i| at + i + end.len());
        out.extend(rest[at..span_end].chars().map(|c| if c == '\n' { '\n' } else { ' ' }));
        rest = &rest[span_end..];
    }
    out.push_str(rest);
    out
}

/// `text` with every element named in `names` blanked out as [`blank_non_markup`] does, from
/// its start tag through its end tag (or its self-closing tag alone). One that is never closed
/// is left for the XML parser to report.
fn blank_elements(text: &str, names: &[&str]) -> String {
    let mut out = text.to_string();
    for name in names {
        let open = format!("<{name}");
        let close = format!("</{name}");
        let mut from = 0;
        while let Some(at) = out[from..].find(&open).map(|i| from + i) {
            let after = at + open.len();
            let boundary = out[after..].chars().next().is_some_and(|c| c.is_whitespace() || c == '>' || c == '/');
            let Some(tag_end) = out[after..].find('>').map(|i| after + i) else { break };
            let end = if !boundary {
                None
            } else if out[..tag_end].ends_with('/') {
                Some(tag_end + 1)
            } else {
                out[tag_end..].find(&close).and_then(|i| out[tag_end + i..].find('>').map(|j| tag_end + i + j + 1))
            };
            let Some(end) = end else {
                from = after;
                continue;
            };
            let blank: String = out[at..end].chars().map(|c| if c == '\n' { '\n' } else { ' ' }).collect();
            out.replace_range(at..end, &blank);
            from = at + blank.len();
        }
    }
    out
}

/// The first numeric attribute that does not parse, as "line N: name=\"value\" is not a number"
/// (or is a xacro expression).
fn find_bad_number(text: &str) -> Option<String> {
    for (line_no, line) in text.lines().enumerate() {
        let mut rest = line;
        while let Some(eq) = rest.find("=\"") {
            let name = rest[..eq].rsplit(|c: char| c.is_whitespace() || c == '<').next().unwrap_or("");
            let after = &rest[eq + 2..];
            let Some(close) = after.find('"') else { break };
            let value = &after[..close];
            if value.contains("$(") || value.contains("${") {
                return Some(format!(
                    "line {}: {name}=\"{value}\" is a xacro expression: this is a .xacro file, run `xacro` on it first \
                     (e.g. `xacro robot.urdf.xacro > robot.urdf`)",
                    line_no + 1
                ));
            }
            if NUMERIC_ATTRIBUTES.contains(&name) && value.split_whitespace().any(|t| t.parse::<f64>().is_err()) {
                return Some(format!("line {}: {name}=\"{value}\" is not a number", line_no + 1));
            }
            rest = &after[close + 1..];
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clean(text: &str) -> (anyhow::Result<String>, Vec<String>) {
        let mut warnings = Vec::new();
        (tolerant_urdf_text(text, &mut warnings), warnings)
    }

    #[test]
    fn a_repeated_visual_material_is_kept_once_with_a_warning() {
        let text = r#"<robot name="r"><link name="a"><visual><geometry><box size="1 1 1"/></geometry>
            <material name="red"/><material name="blue"/></visual></link></robot>"#;
        let (out, warnings) = clean(text);
        let out = out.unwrap();
        assert_eq!(out.matches("<material").count(), 1, "{out}");
        assert!(out.contains("red") && !out.contains("blue"), "{out}");
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].contains("link 'a'") && warnings[0].contains("<material>"), "{warnings:?}");
    }

    #[test]
    fn differing_repeats_that_change_the_dynamics_are_an_error_naming_the_link() {
        let text = r#"<robot name="r"><link name="leg"><inertial><mass value="1"/><mass value="2"/>
            <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link></robot>"#;
        let err = format!("{:#}", clean(text).0.unwrap_err());
        assert!(err.contains("link 'leg'") && err.contains("<mass>"), "{err}");
        // A copy of the same mass is harmless.
        let copy = text.replace("value=\"2\"", "value=\"1\"");
        let (out, warnings) = clean(&copy);
        assert_eq!(out.unwrap().matches("<mass").count(), 1);
        assert!(warnings[0].contains("a copy"), "{warnings:?}");
    }

    #[test]
    fn unknown_elements_are_dropped_and_ros_extensions_silently() {
        let text = r#"<robot name="r"><gazebo reference="a"/><transmission name="t"/><sensor name="s"/>
            <link name="a"><contact_coefficients mu="1"/></link>
            <joint name="j" type="fixed"><parent link="a"/><child link="b"/><limit effort="1"/><limit effort="1"/>
            </joint><link name="b"/></robot>"#;
        let (out, warnings) = clean(text);
        let out = out.unwrap();
        assert!(!out.contains("gazebo") && !out.contains("sensor") && !out.contains("contact_coefficients"));
        assert_eq!(out.matches("<limit").count(), 1, "{out}");
        assert_eq!(warnings.len(), 3, "{warnings:?}");
        assert!(warnings.iter().any(|w| w.contains("robot: unknown element <sensor>")), "{warnings:?}");
        assert!(warnings.iter().any(|w| w.contains("link 'a': unknown element <contact_coefficients>")));
        assert!(warnings.iter().any(|w| w.contains("joint 'j': repeated <limit>")), "{warnings:?}");
    }

    #[test]
    fn comments_processing_instructions_cdata_and_a_byte_order_mark_are_not_read_as_markup() {
        let text = "\u{feff}<?xml version=\"1.0\"?>\n<robot name=\"r\">\n\
            <!-- <xacro:if value=\"$(arg DEBUG)\"> <mass value=\"x\"/> -->\n\
            <link name=\"a\"><inertial><mass value=\"1\"/><![CDATA[ value=\"y\" ]]>\n\
            <inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial></link></robot>";
        let (out, warnings) = clean(text);
        let out = out.unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        // urdf-rs, which reads the cleaned text, skips the comment as XML does.
        let robot = rapier3d_urdf::urdf_rs::read_from_string(&out).unwrap_or_else(|e| panic!("{e}\n{out}"));
        assert_eq!(robot.links[0].inertial.mass.value, 1.0);
        // Line numbers still count the blanked lines.
        let bad = text.replace("<mass value=\"1\"/>", "<mass value=\"z\"/>");
        let err = format!("{:#}", clean(&bad).0.unwrap_err());
        assert!(err.contains("line 4") && err.contains("value=\"z\""), "{err}");
    }

    #[test]
    fn a_xacro_expression_outside_a_comment_says_the_file_needs_xacro_first() {
        let text = "<robot name=\"r\">\n<link name=\"a\"><inertial><mass value=\"${mass}\"/></inertial></link>\n\
            <joint name=\"j\" type=\"fixed\"><origin xyz=\"$(arg x) 0 0\"/></joint></robot>";
        let err = format!("{:#}", clean(text).0.unwrap_err());
        assert!(err.contains("line 2") && err.contains("${mass}") && err.contains("run `xacro`"), "{err}");
    }

    #[test]
    fn ros_extensions_are_dropped_unread_wherever_they_are() {
        let text = "<robot name=\"r\">\n<gazebo reference=\"${prefix}_foot\"><kp value=\"big\"/></gazebo>\n\
            <transmission name=\"t\"><joint name=\"ghost\"><hardwareInterface>x</hardwareInterface></joint>\n\
            <mechanicalReduction value=\"$(arg r)\"/></transmission>\n<gazebo/>\n\
            <ros2_control name=\"s\" type=\"system\"><joint name=\"ghost2\"/></ros2_control>\n\
            <link name=\"a\"><gazebo><link name=\"fake\"/></gazebo><inertial><mass value=\"1\"/>\n\
            <inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial></link></robot>";
        let (out, warnings) = clean(text);
        let out = out.unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        let robot = rapier3d_urdf::urdf_rs::read_from_string(&out).unwrap_or_else(|e| panic!("{e}\n{out}"));
        assert_eq!(robot.links.iter().map(|l| l.name.as_str()).collect::<Vec<_>>(), ["a"]);
        assert!(robot.joints.is_empty(), "{:?}", robot.joints);
        // Outside them, a bad number is still an error naming its line (counted through the blanked blocks).
        let bad = text.replace("<mass value=\"1\"/>", "<mass value=\"${m}\"/>");
        let err = format!("{:#}", clean(&bad).0.unwrap_err());
        assert!(err.contains("line 7") && err.contains("${m}"), "{err}");
        // A name that only starts like an extension's is not one.
        assert_eq!(blank_elements("<gazebos a=\"1\"/>", &ROS_EXTENSIONS), "<gazebos a=\"1\"/>");
    }

    #[test]
    fn bad_numbers_and_broken_xml_are_errors_that_say_where() {
        let err = format!(
            "{:#}",
            clean("<robot name=\"r\">\n<link name=\"a\"><inertial><mass value=\"x1\"/>").0.unwrap_err()
        );
        assert!(err.contains("line 2") && err.contains("value=\"x1\""), "{err}");
        let err = format!("{:#}", clean("<robot name=\"r\"><link name=\"a\">").0.unwrap_err());
        assert!(err.contains("malformed URDF"), "{err}");
        let err = format!("{:#}", clean("<sdf/>").0.unwrap_err());
        assert!(err.contains("<sdf>"), "{err}");
    }
}
