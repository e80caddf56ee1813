//! Labelled object crops for the recogniser (models/recogniser/MODEL_CARD.md): cluttered
//! tabletop scenes ([`recognition_scene`]) segmented and cropped by graspd's own code
//! (`objects_on_plane`, `object_crop`), each segment labelled with the object that most of its
//! pixels show.
//!
//! A scene holds 2–6 objects: 55 % the 12 textured YCB objects of the test data (standing, any
//! yaw), the rest procedural parts painted at random ([`crate::scene`]), which are `unknown`.
//! A YCB object shows its scanned texture (each channel times 0.85–1.15, a sensor's white
//! balance) 80 % of the time, and otherwise one flat colour, the texture's mean, as graspd-sim
//! renders it. With `unseen`, the chips can (never in training; it has no texture, so it is
//! painted at random) joins the YCB draw as a 13th object and is `unknown` too: how the network
//! treats a real object it has not seen.

use crate::scene::{Appearance, Scene, Texture, random_primitive, ycb_object};
use graspd_core::perception::recognition::{ObjectCrop, UNKNOWN, object_crop};
use graspd_core::perception::segmentation::{SegmentationParams, objects_on_plane};
use graspd_core::perception::{CloudFrame, PixelCloud, depth_to_cloud};
use graspd_testkit::Object;
use graspd_testkit::texture::texture;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The objects the recogniser knows: the 12 textured YCB objects of the test data.
pub const KNOWN: [Object; 12] = [
    Object::MasterChefCan,
    Object::CrackerBox,
    Object::SugarBox,
    Object::TomatoSoupCan,
    Object::MustardBottle,
    Object::TunaFishCan,
    Object::PuddingBox,
    Object::GelatinBox,
    Object::PottedMeatCan,
    Object::Banana,
    Object::Apple,
    Object::Orange,
];

/// The class names in output order: the known objects' short names, then `unknown`.
pub fn class_names() -> Vec<String> {
    KNOWN
        .iter()
        .map(|o| o.short_name().to_string())
        .chain([UNKNOWN.to_string()])
        .collect()
}

/// The class index of a scene object's identity.
pub fn class_of(identity: Option<Object>) -> u8 {
    identity
        .and_then(|o| KNOWN.iter().position(|k| *k == o))
        .unwrap_or(KNOWN.len()) as u8
}

/// A cluttered scene from `seed` (module docs).
pub fn recognition_scene(seed: u64, unseen: bool) -> graspd_testkit::Result<Scene> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let count = rng.random_range(2..=6usize);
    let pool = KNOWN.len() + usize::from(unseen);
    Scene::assemble(
        rng,
        count,
        |rng| {
            if rng.random_bool(0.55) {
                let k = rng.random_range(0..pool);
                let object = KNOWN.get(k).copied().unwrap_or(Object::ChipsCan);
                Ok((ycb_object(object)?, Some(object)))
            } else {
                let kind = rng.random_range(30..100);
                Ok((random_primitive(rng, kind), None))
            }
        },
        |rng, identity| {
            let scan = identity.and_then(|o| texture(o).ok().flatten().map(|t| (o, t)));
            match scan {
                Some((object, texture)) => {
                    if rng.random_bool(0.8) {
                        Appearance::Scanned {
                            object,
                            texture,
                            gain: [0; 3].map(|_| rng.random_range(0.85..1.15)),
                        }
                    } else {
                        let c = texture.mean_colour();
                        Appearance::Painted {
                            colors: [c, c],
                            texture: Texture::Plain,
                        }
                    }
                }
                None => Appearance::random_paint(rng),
            }
        },
    )
}

/// One segment and its label.
pub struct Labelled {
    pub crop: ObjectCrop,
    /// Index into [`class_names`]; `None` for a segment no object covers 80 % of (objects
    /// touching in the view).
    pub class: Option<u8>,
    /// What it is: the index into [`KNOWN`], [`SOURCE_UNSEEN`] for the chips can,
    /// [`SOURCE_PROCEDURAL`] for a procedural part.
    pub source: u8,
}

/// [`Labelled::source`] of the chips can (`unseen`).
pub const SOURCE_UNSEEN: u8 = 12;
/// [`Labelled::source`] of a procedural object.
pub const SOURCE_PROCEDURAL: u8 = 255;

/// What one scene gave: every segment graspd finds, in its order.
pub struct SceneCrops {
    pub segments: Vec<Labelled>,
    /// Objects placed in the scene.
    pub placed: usize,
}

impl SceneCrops {
    /// The segments with a label.
    pub fn labelled(&self) -> impl Iterator<Item = &Labelled> {
        self.segments.iter().filter(|s| s.class.is_some())
    }

    /// Segments without one.
    pub fn mixed(&self) -> usize {
        self.segments.iter().filter(|s| s.class.is_none()).count()
    }
}

/// Scene `i` of a split with `seed` (drawn from `seed · 1 000 003 + i`), segmented and cropped
/// as graspd does it.
pub fn recognition_sample(seed: u64, i: usize, unseen: bool) -> Result<SceneCrops, String> {
    let scene = recognition_scene(seed.wrapping_mul(1_000_003).wrapping_add(i as u64), unseen)
        .map_err(|e| e.to_string())?;
    let k = scene.camera.intrinsics;
    let frame = scene.render(&vec![true; k.height], &vec![true; k.width]);
    let decoded = frame.decoded(&k);
    let cloud: PixelCloud = depth_to_cloud(&decoded, CloudFrame::World);
    let (plane, clusters, _) =
        objects_on_plane(&cloud.cloud.points, None, &SegmentationParams::default());
    let mut segments = Vec::new();
    for indices in clusters {
        let mut votes = vec![0usize; scene.identities.len() + 1];
        for &i in &indices {
            votes[frame.objects[cloud.pixels[i] as usize] as usize] += 1;
        }
        let (best, n) = votes
            .iter()
            .enumerate()
            .max_by_key(|(k, n)| (**n, std::cmp::Reverse(*k)))
            .map(|(k, n)| (k, *n))
            .unwrap_or((0, 0));
        let crop = object_crop(&decoded, &cloud, &indices, plane.as_ref());
        if best == 0 || n * 5 < indices.len() * 4 {
            segments.push(Labelled {
                crop,
                class: None,
                source: SOURCE_PROCEDURAL,
            });
            continue;
        }
        let identity = scene.identities[best - 1];
        segments.push(Labelled {
            crop,
            class: Some(class_of(identity)),
            source: match identity {
                None => SOURCE_PROCEDURAL,
                Some(o) => KNOWN
                    .iter()
                    .position(|k| *k == o)
                    .map_or(SOURCE_UNSEEN, |k| k as u8),
            },
        });
    }
    Ok(SceneCrops {
        segments,
        placed: scene.identities.len(),
    })
}
