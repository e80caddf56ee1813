//! The force limits of a model's actuators, per joint ([`Joint::effort`]): what the squeeze can
//! ask of a finger's servos (planning/final_configuration/squeeze.rs).
//!
//! MuJoCo semantics: an actuator (`position`, `motor`, `general`, …) drives a joint or a fixed
//! tendon (`joint=`, `jointinparent=`, `tendon=`); its force is clamped to `forcerange` when
//! `forcelimited` is true (`auto`: when a range is given and the compiler's `autolimits` is on)
//! and reaches a joint × its `gear` (through a fixed tendon, × the joint's `coef` too). A joint's
//! own `actuatorfrcrange` clamps the sum of its actuators' forces. A joint is force-limited when
//! every actuator driving it is; actuators on spatial tendons or sites are not joint servos and
//! are skipped.

use super::super::kinematic_tree::KinematicTree;
use super::super::xml::{self, Element};
use super::attributes::{Attrs, Compiler, Defaults, parse_bool, resolve};
use super::err;
use crate::error::FieldError;
use std::collections::HashMap;

/// The largest force `a` allows through `range_key` (`forcerange`, `actuatorfrcrange`) when
/// `limited_key` makes it a limit; None when unlimited.
fn force_limit(
    a: &Attrs,
    compiler: &Compiler,
    range_key: &str,
    limited_key: &str,
) -> Result<Option<f64>, FieldError> {
    let range = a.numbers(range_key, 2)?;
    let limited = match a.get(limited_key).unwrap_or("auto") {
        "auto" => range.is_some() && compiler.autolimits,
        s => parse_bool(a.el, limited_key, s)?,
    };
    match range {
        Some(r) if limited => {
            if r[0] > r[1] {
                return Err(err(a.el, format!("{range_key} must be low high")));
            }
            Ok(Some(r[0].abs().max(r[1].abs())))
        }
        None if limited => Err(err(a.el, format!("{limited_key} without a {range_key}"))),
        _ => Ok(None),
    }
}

/// A joint's own `actuatorfrcrange` limit (None when it sets none).
pub(super) fn joint_limit(a: &Attrs, compiler: &Compiler) -> Result<Option<f64>, FieldError> {
    force_limit(a, compiler, "actuatorfrcrange", "actuatorfrclimited")
}

/// Sets each actuated joint's [`Joint::effort`](crate::hand::kinematics::kinematic_tree::Joint)
/// from the `<actuator>` sections of `root` (the joints' own limits already set).
pub(super) fn read_actuator_limits(
    root: &Element,
    defaults: &Defaults,
    compiler: &Compiler,
    tree: &mut KinematicTree,
) -> Result<(), FieldError> {
    // Fixed tendons: name → (joint, coefficient).
    let mut tendons: HashMap<&str, Vec<(&str, f64)>> = HashMap::new();
    for t in root.children_named("tendon") {
        for f in t.children_named("fixed") {
            let Some(name) = f.attr("name") else { continue };
            let mut joints = Vec::new();
            for j in f.children_named("joint") {
                let a = resolve(defaults, j, "main")?;
                let joint = a
                    .get("joint")
                    .ok_or_else(|| err(j, "a tendon's joint needs 'joint'"))?;
                let coef = a.numbers("coef", 1)?.map_or(1.0, |v| v[0]);
                joints.push((joint, coef));
            }
            tendons.insert(name, joints);
        }
    }
    // Per joint: the summed limits of its actuators, None once one is unlimited.
    let mut sums: HashMap<usize, Option<f64>> = HashMap::new();
    for section in root.children_named("actuator") {
        for c in &section.children {
            let a = resolve(defaults, c, "main")?;
            let driven: Vec<(&str, f64)> =
                match (a.get("joint").or(a.get("jointinparent")), a.get("tendon")) {
                    (Some(j), _) => vec![(j, 1.0)],
                    (None, Some(t)) => match tendons.get(t) {
                        Some(js) => js.clone(),
                        None => continue,
                    },
                    _ => continue,
                };
            // `gear` is up to six numbers; a joint or tendon transmission uses the first.
            let gear = match a.get("gear") {
                None => 1.0,
                Some(g) => xml::numbers_up_to(g, 6)
                    .ok_or_else(|| err(c, format!("gear='{g}' must be 1 to 6 finite numbers")))?[0]
                    .abs(),
            };
            let limit = force_limit(&a, compiler, "forcerange", "forcelimited")?;
            for (joint, coef) in driven {
                let j = tree
                    .joint_index(joint)
                    .ok_or_else(|| err(c, format!("joint '{joint}' is not in the model")))?;
                let add = limit.map(|f| f * gear * coef.abs());
                let sum = sums.entry(j).or_insert(Some(0.0));
                *sum = match (*sum, add) {
                    (Some(s), Some(x)) => Some(s + x),
                    _ => None,
                };
            }
        }
    }
    for (j, sum) in sums {
        let joint = &mut tree.joints[j];
        joint.effort = match (joint.effort, sum) {
            (Some(own), Some(s)) => Some(own.min(s)),
            (own, s) => own.or(s),
        };
    }
    Ok(())
}
