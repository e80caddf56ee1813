//! The object by name (dissertation §3.2.1, "Object Detection"): `hints.object = "apple"`
//! makes the target the segmented object that the recogniser takes for an apple.
//!
//! The dissertation localises and recognises with one detector (YOLO, fine-tuned on its own
//! table-object data set). graspd already segments the objects on the table from depth
//! ([`super::segmentation`]), so the learned part only has to say *what* each segment is: a
//! small CNN ([`model`], models/recogniser/MODEL_CARD.md) reads each object's crop and size
//! ([`crop`]) and gives P(class | object) over the known classes and `unknown`.
//!
//! The named object is the one, among the objects whose most probable class is the name,
//! with the highest probability of it ([`find_named`]). A name the recogniser does not know,
//! or one that no object in view is taken for, is refused as not found, listing what was
//! found.

pub mod crop;
pub mod model;

pub use crop::{CROP_CHANNELS, CROP_SIDE, ObjectCrop, SIZE_FEATURES, object_crop};
pub use model::{META_CLASSES, RecognitionModel, UNKNOWN};

use super::depth_to_cloud::PixelCloud;
use super::grasp_type::ModelError;
use super::rgbd::DecodedFrame;
use super::segmentation::Cluster;
use crate::cloud::Plane;
use crate::error::FieldError;
use serde::{Deserialize, Serialize};

/// What the recogniser takes one segmented object for.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecognisedObject {
    /// The most probable class (`unknown` for none of the known objects).
    pub class: String,
    /// Its probability.
    pub probability: f64,
    /// Mean (u, v) of the object's pixels.
    pub pixel_centroid: [f64; 2],
    /// The object's points.
    pub points: usize,
    /// P(class | object) in the model's class order.
    #[serde(skip)]
    pub probabilities: Vec<f64>,
}

/// Runs the recogniser on each of `clusters` (one batch).
pub fn recognise(
    model: &RecognitionModel,
    frame: &DecodedFrame,
    cloud: &PixelCloud,
    clusters: &[Cluster],
    plane: Option<&Plane>,
) -> Result<Vec<RecognisedObject>, ModelError> {
    let crops: Vec<ObjectCrop> = clusters
        .iter()
        .map(|c| object_crop(frame, cloud, &c.indices, plane))
        .collect();
    let probs = model.classify(&crops)?;
    Ok(clusters
        .iter()
        .zip(probs)
        .map(|(c, p)| {
            let best = argmax(&p);
            RecognisedObject {
                class: model.classes()[best].clone(),
                probability: p[best],
                pixel_centroid: [c.pixel_centroid.0, c.pixel_centroid.1],
                points: c.indices.len(),
                probabilities: p,
            }
        })
        .collect())
}

fn argmax(p: &[f64]) -> usize {
    p.iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))
        .map_or(0, |(k, _)| k)
}

/// A name as the recogniser's classes spell it: lower case, words joined by `_`, without a
/// YCB number (`"Tomato soup can"`, `"005_tomato_soup_can"` → `tomato_soup_can`).
pub fn class_name(name: &str) -> String {
    let words: Vec<String> = name
        .split(|c: char| c.is_whitespace() || c == '-' || c == '_')
        .filter(|w| !w.is_empty())
        .map(str::to_lowercase)
        .collect();
    let skip = usize::from(words.len() > 1 && words[0].chars().all(|c| c.is_ascii_digit()));
    words[skip..].join("_")
}

/// Why the named object was not chosen: the name is unknown, or no object in view is taken
/// for it. The message lists the objects found and the names known.
#[derive(Debug, Clone, PartialEq)]
pub struct NotFound(pub FieldError);

/// The index (into `objects`) of the object named `name` (see the module docs); `classes`:
/// the recogniser's classes.
pub fn find_named(
    name: &str,
    classes: &[String],
    objects: &[RecognisedObject],
) -> Result<usize, NotFound> {
    let wanted = class_name(name);
    let found = || {
        if objects.is_empty() {
            "no object".to_string()
        } else {
            objects
                .iter()
                .map(|o| {
                    format!(
                        "{} (p {:.2}) at pixel ({:.0}, {:.0})",
                        o.class, o.probability, o.pixel_centroid[0], o.pixel_centroid[1]
                    )
                })
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    let known = || {
        classes
            .iter()
            .filter(|c| *c != UNKNOWN)
            .cloned()
            .collect::<Vec<_>>()
            .join(", ")
    };
    let Some(k) = classes.iter().position(|c| *c == wanted && c != UNKNOWN) else {
        return Err(NotFound(FieldError::new(
            "hints.object",
            format!(
                "{name:?} is not an object the recogniser knows ({}); found in view: {}",
                known(),
                found()
            ),
        )));
    };
    objects
        .iter()
        .enumerate()
        .filter(|(_, o)| o.class == wanted)
        .max_by(|a, b| {
            a.1.probabilities[k]
                .total_cmp(&b.1.probabilities[k])
                .then(b.0.cmp(&a.0))
        })
        .map(|(i, _)| i)
        .ok_or_else(|| {
            NotFound(FieldError::new(
                "hints.object",
                format!("no {wanted} in view; found: {}", found()),
            ))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn object(class: &str, probabilities: Vec<f64>) -> RecognisedObject {
        let best = argmax(&probabilities);
        RecognisedObject {
            class: class.into(),
            probability: probabilities[best],
            pixel_centroid: [10.0, 20.0],
            points: 500,
            probabilities,
        }
    }

    fn classes() -> Vec<String> {
        ["apple", "tomato_soup_can", UNKNOWN]
            .map(String::from)
            .to_vec()
    }

    #[test]
    fn names_are_spelled_as_the_classes() {
        assert_eq!(class_name("Tomato soup can"), "tomato_soup_can");
        assert_eq!(class_name("005_tomato_soup_can"), "tomato_soup_can");
        assert_eq!(class_name(" apple "), "apple");
        assert_eq!(class_name("mustard-bottle"), "mustard_bottle");
        assert_eq!(class_name("7up"), "7up");
    }

    #[test]
    fn the_most_probable_of_the_objects_taken_for_the_name() {
        let objects = vec![
            object("apple", vec![0.6, 0.1, 0.3]),
            object("tomato_soup_can", vec![0.45, 0.5, 0.05]),
            object("apple", vec![0.9, 0.05, 0.05]),
        ];
        assert_eq!(find_named("apple", &classes(), &objects), Ok(2));
        // The can is more likely an apple than the first apple is, but it is taken for a can.
        assert_eq!(find_named("013_apple", &classes(), &objects[..2]), Ok(0));
        assert_eq!(find_named("Tomato soup can", &classes(), &objects), Ok(1));
    }

    #[test]
    fn unknown_or_absent_names_are_not_found_and_say_what_was_found() {
        let objects = vec![object("apple", vec![0.9, 0.05, 0.05])];
        let NotFound(e) = find_named("banana", &classes(), &objects).unwrap_err();
        assert_eq!(e.field, "hints.object");
        assert!(
            e.message.contains("knows (apple, tomato_soup_can)"),
            "{}",
            e.message
        );
        assert!(
            e.message.contains("apple (p 0.90) at pixel (10, 20)"),
            "{}",
            e.message
        );
        let NotFound(e) = find_named("tomato soup can", &classes(), &objects).unwrap_err();
        assert!(
            e.message.starts_with("no tomato_soup_can in view"),
            "{}",
            e.message
        );
        // `unknown` is a class, not a name.
        assert!(find_named("unknown", &classes(), &objects).is_err());
        assert!(find_named("apple", &classes(), &[]).is_err());
    }
}
