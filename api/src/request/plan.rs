//! A plan request in domain terms, as both transports produce it.

use graspd_core::cloud::PointCloud;
use graspd_core::perception::{RgbdFrame, TargetHint};
use graspd_core::{FieldError, HandDescription, PlanHints, PlannerOptions};

/// What the plan is computed from.
#[derive(Debug, Clone, PartialEq)]
pub enum PlanSource {
    /// A cloud as decoded at the edge; the facade validates it.
    Cloud(PointCloud),
    /// An RGB-D frame as received; the facade decodes and validates it (method.md §4).
    Rgbd(Box<RgbdFrame>),
}

/// Which hand to plan for.
#[derive(Debug, Clone, PartialEq)]
pub enum HandChoice {
    /// A hand of the catalog.
    Name(String),
    /// An inline description, validated like the data files.
    Inline(Box<HandDescription>),
}

/// The longest `hints.object` accepted, bytes.
pub const MAX_OBJECT_NAME: usize = 128;

/// Hints that only make sense on an image (RGB-D input); with a cloud they are refused rather
/// than ignored.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ImageHints {
    /// The object at this pixel (u, v), and the attention point there.
    pub attention_pixel: Option<(u32, u32)>,
    /// The object with most pixels in [u_min, u_max) × [v_min, v_max).
    pub region: Option<[u32; 4]>,
    /// The object the recogniser takes for this name (empty: none).
    pub object: String,
    /// The most salient object (the default without a pixel or region).
    pub most_salient: bool,
}

impl ImageHints {
    /// The first hint given, by its field name.
    pub fn field(&self) -> Option<&'static str> {
        if self.attention_pixel.is_some() {
            Some("hints.attention_pixel")
        } else if self.region.is_some() {
            Some("hints.region")
        } else if !self.object.is_empty() {
            Some("hints.object")
        } else if self.most_salient {
            Some("hints.most_salient")
        } else {
            None
        }
    }

    /// The segmentation's target hint; errors name the conflicting hint.
    pub fn target(&self) -> Result<TargetHint, FieldError> {
        if !self.object.is_empty() {
            if self.attention_pixel.is_some() || self.region.is_some() {
                return Err(FieldError::new(
                    "hints.object",
                    "give one of attention_pixel, region and object",
                ));
            }
            if self.object.trim().is_empty() || self.object.len() > MAX_OBJECT_NAME {
                return Err(FieldError::new(
                    "hints.object",
                    format!("needs a name of 1 to {MAX_OBJECT_NAME} characters"),
                ));
            }
            return Ok(TargetHint::Object(self.object.clone()));
        }
        match (self.attention_pixel, self.region) {
            (Some(_), Some(_)) => Err(FieldError::new(
                "hints.region",
                "give either attention_pixel or region, not both",
            )),
            (Some((u, v)), None) => Ok(TargetHint::Pixel { u, v }),
            (None, Some([u_min, v_min, u_max, v_max])) => {
                if u_min >= u_max || v_min >= v_max {
                    return Err(FieldError::new(
                        "hints.region",
                        format!(
                            "is empty: u {u_min}..{u_max}, v {v_min}..{v_max} (need u_min < u_max and v_min < v_max)"
                        ),
                    ));
                }
                Ok(TargetHint::Region {
                    u_min,
                    v_min,
                    u_max,
                    v_max,
                })
            }
            (None, None) => Ok(TargetHint::Auto),
        }
    }
}

/// What to return besides the plan.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct OutputOptions {
    /// Return the grasp-type model's six maps with the longer side at most this many pixels
    /// (0 = do not; RGB-D input).
    pub probability_maps_max_side: u32,
    /// Draw the overlay PNG (ROI, attention point, heat map of s*, contacts, opposition; RGB-D
    /// input).
    pub overlay: bool,
    /// Return the candidates also in the layout of `moveit_msgs/Grasp`
    /// (`graspd_core::planning::moveit_layout`).
    pub moveit_grasps: bool,
    /// The frame the plan is in, for the MoveIt grasps' headers ([`Self::in_frame`]).
    pub frame_id: String,
    /// Return the plan as a binary glTF scene (`graspd_core::plan_scene`).
    pub scene_glb: bool,
}

impl OutputOptions {
    /// The frame asked for, else the input's (a cloud's `frame_id`): what the MoveIt grasps'
    /// headers name.
    pub fn in_frame(mut self, input_frame: &str) -> Self {
        if self.frame_id.is_empty() {
            self.frame_id = input_frame.to_string();
        }
        self
    }
}

/// One plan request in domain terms, as both transports produce it.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanRequest {
    pub source: PlanSource,
    /// Further views of the scene (RGB-D input only; `extra_views`).
    pub extra_views: Vec<RgbdFrame>,
    pub hand: HandChoice,
    pub options: PlannerOptions,
    pub hints: PlanHints,
    pub image_hints: ImageHints,
    pub output: OutputOptions,
}
