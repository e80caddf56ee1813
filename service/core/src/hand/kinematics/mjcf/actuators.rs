//! Joint efforts from an MJCF's actuators (issue 15): the largest torque (hinge, N·m) or force
//! (slide, N) the actuators can put on each joint, which bounds how hard a finger can press
//! (`KinematicHand::grip_capacity`).
//!
//! - Actuators of every kind (`general`, `motor`, `position`, `velocity`, `intvelocity`,
//!   `damper`, `cylinder`, `muscle`) with a `joint` (or `jointinparent`) transmission, or a
//!   fixed `<tendon>`'s; site and body transmissions move no joint and are skipped.
//! - An actuator's force is limited by `forcerange` when `forcelimited` is true, or "auto" (the
//!   default) with autolimits on and a `forcerange` given (MuJoCo's rule). Its class is its
//!   `class` or `main`; MuJoCo keeps one actuator default per class whichever element set it,
//!   so an attribute is looked up on the element's own kind first, then on the others.
//! - A joint receives |gear[0] · coef| times the force (coef 1 for a joint transmission, the
//!   tendon's coefficient for a fixed tendon); several actuators on one joint add up; one
//!   unlimited actuator leaves the joint unlimited (`None`), as does no actuator at all. A
//!   joint's `actuatorfrcrange` (read with the joint) clamps the total.

use super::{Defaults, FIELD, err, parse_bool};
use crate::error::FieldError;
use crate::hand::kinematics::kinematic_tree::KinematicTree;
use crate::hand::kinematics::xml::{self, Element};
use std::collections::HashMap;

/// The actuator elements, in the order their defaults are looked up after the element's own.
const KINDS: [&str; 8] = [
    "general",
    "motor",
    "position",
    "velocity",
    "intvelocity",
    "damper",
    "cylinder",
    "muscle",
];

/// Sets every joint's `effort` from the model's `<actuator>` and `<tendon>` sections (module
/// doc).
pub(super) fn read_efforts(
    root: &Element,
    defaults: &Defaults,
    autolimits: bool,
    tree: &mut KinematicTree,
) -> Result<(), FieldError> {
    let tendons = fixed_tendons(root, tree)?;
    // Per joint: the summed limit of its actuators, None once one of them is unlimited.
    let mut total: HashMap<usize, Option<f64>> = HashMap::new();
    for section in root.children_named("actuator") {
        for el in section
            .children
            .iter()
            .filter(|c| KINDS.contains(&c.name.as_str()))
        {
            let get = attr_lookup(defaults, el)?;
            let gear = match get("gear") {
                None => 1.0,
                Some(s) => xml::numbers_up_to(s, 6)
                    .and_then(|v| v.first().copied())
                    .ok_or_else(|| err(el, format!("gear='{s}' must be up to 6 numbers")))?,
            };
            let limit = actuator_limit(el, &get, autolimits)?;
            let moved: Vec<(usize, f64)> = match (
                el.attr("joint").or(el.attr("jointinparent")),
                el.attr("tendon"),
            ) {
                (Some(j), _) => {
                    let i = tree.joint_index(j).ok_or_else(|| {
                        err(
                            el,
                            format!("joint '{j}' is not a hinge or slide joint of the model"),
                        )
                    })?;
                    vec![(i, 1.0)]
                }
                (None, Some(t)) => match tendons.get(t) {
                    Some(joints) => joints.clone(),
                    // A spatial tendon (or one the model lacks) moves no joint directly.
                    None => continue,
                },
                (None, None) => continue,
            };
            for (j, coef) in moved {
                let add = limit.map(|f| (gear * coef).abs() * f);
                let slot = total.entry(j).or_insert(Some(0.0));
                *slot = match (*slot, add) {
                    (Some(a), Some(b)) => Some(a + b),
                    _ => None,
                };
            }
        }
    }
    for (j, joint) in tree.joints.iter_mut().enumerate() {
        joint.effort = match (total.get(&j).copied().flatten(), joint.effort) {
            // Not actuated: nothing to clamp.
            _ if !total.contains_key(&j) => None,
            (Some(t), Some(clamp)) => Some(t.min(clamp)),
            (Some(t), None) => Some(t),
            (None, clamp) => clamp,
        };
    }
    Ok(())
}

/// An attribute of actuator `el`: its own, else its class's for its kind, else for another
/// actuator kind.
fn attr_lookup<'a>(
    defaults: &'a Defaults,
    el: &'a Element,
) -> Result<impl Fn(&str) -> Option<&'a str> + 'a, FieldError> {
    let class = el.attr("class").unwrap_or("main");
    let c = defaults
        .classes
        .get(class)
        .ok_or_else(|| err(el, format!("unknown default class '{class}'")))?;
    Ok(move |name: &str| {
        el.attr(name).or_else(|| {
            std::iter::once(el.name.as_str())
                .chain(KINDS)
                .find_map(|k| c.0.get(k).and_then(|a| a.get(name)))
                .map(|s| s.as_str())
        })
    })
}

/// The largest |force| actuator `el` exerts, None when unlimited.
fn actuator_limit<'a>(
    el: &Element,
    get: &impl Fn(&str) -> Option<&'a str>,
    autolimits: bool,
) -> Result<Option<f64>, FieldError> {
    let range = match get("forcerange") {
        None => None,
        Some(s) => Some(
            xml::numbers(s, 2)
                .ok_or_else(|| err(el, format!("forcerange='{s}' must be 2 finite numbers")))?,
        ),
    };
    let limited = match get("forcelimited").unwrap_or("auto") {
        "auto" => range.is_some() && autolimits,
        s => parse_bool(el, "forcelimited", s)?,
    };
    match range {
        Some(r) if limited => Ok(Some(r[0].abs().max(r[1].abs()))),
        None if limited => Err(FieldError::new(
            format!("{FIELD}.actuator.forcerange"),
            format!("{}: forcelimited actuator without a forcerange", el.at()),
        )),
        _ => Ok(None),
    }
}

/// Fixed tendons by name: the joints they span and their coefficients.
fn fixed_tendons(
    root: &Element,
    tree: &KinematicTree,
) -> Result<HashMap<String, Vec<(usize, f64)>>, FieldError> {
    let mut out = HashMap::new();
    for section in root.children_named("tendon") {
        for t in section.children_named("fixed") {
            let Some(name) = t.attr("name") else { continue };
            let mut joints = Vec::new();
            for j in t.children_named("joint") {
                let Some(jn) = j.attr("joint") else {
                    return Err(err(j, "needs joint"));
                };
                let i = tree.joint_index(jn).ok_or_else(|| {
                    err(
                        j,
                        format!("joint '{jn}' is not a hinge or slide joint of the model"),
                    )
                })?;
                let coef = match j.attr("coef") {
                    None => 1.0,
                    Some(s) => s
                        .trim()
                        .parse::<f64>()
                        .ok()
                        .filter(|c| c.is_finite())
                        .ok_or_else(|| err(j, format!("coef='{s}' must be a number")))?,
                };
                joints.push((i, coef));
            }
            out.insert(name.to_string(), joints);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use crate::hand::kinematics::mjcf::parse_mjcf;
    use std::path::Path;

    /// Two hinges and a slide; `actuators` is the `<actuator>` section.
    fn efforts(joint_attrs: &str, actuators: &str) -> Vec<Option<f64>> {
        let xml = format!(
            r#"<mujoco><default><motor forcerange="-2 2"/><default class="weak">
                 <position forcerange="-0.5 0.5"/></default></default>
               <worldbody><body name="a"><joint name="j0" {joint_attrs}/>
                 <body name="b"><joint name="j1"/><body name="c"><joint name="s" type="slide"/>
               </body></body></body></worldbody>
               <tendon><fixed name="t"><joint joint="j0" coef="2"/><joint joint="j1" coef="-1"/>
               </fixed></tendon>
               <actuator>{actuators}</actuator></mujoco>"#
        );
        let t = parse_mjcf(&xml, Path::new("."), "test").unwrap();
        t.joints.iter().map(|j| j.effort).collect()
    }

    /// Gear, tendon coefficients and class defaults scale the force onto the joints; two
    /// actuators on one joint add up; an unactuated joint has none.
    #[test]
    fn efforts_follow_gear_tendon_and_defaults() {
        let e = efforts(
            "",
            r#"<motor joint="j0" gear="3"/><position class="weak" tendon="t"/>"#,
        );
        // j0: 3 × 2 (main's motor default) + 2 × 0.5 (the tendon); j1: |−1| × 0.5.
        assert_eq!(e, [Some(7.0), Some(0.5), None]);
    }

    /// `forcelimited="false"` makes the joint unlimited; the joint's `actuatorfrcrange` clamps
    /// the total; a forcelimited actuator without a range is refused.
    #[test]
    fn unlimited_actuators_and_joint_clamps() {
        let e = efforts(
            "",
            r#"<motor joint="j0" forcelimited="false"/><motor joint="s"/>"#,
        );
        assert_eq!(e, [None, None, Some(2.0)]);
        let e = efforts(
            r#"actuatorfrcrange="-1.5 1""#,
            r#"<motor joint="j0"/><motor joint="j0"/>"#,
        );
        assert_eq!(e[0], Some(1.5));
        let xml = r#"<mujoco><worldbody><body><joint name="j"/></body></worldbody>
            <actuator><motor joint="j" forcelimited="true"/></actuator></mujoco>"#;
        let err = parse_mjcf(xml, Path::new("."), "test").unwrap_err();
        assert!(err.message.contains("forcerange"), "{}", err.message);
    }
}
