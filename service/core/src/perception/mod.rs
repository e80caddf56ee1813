//! Perception (method.md §4, dissertation ch. 4.2 and 5.3.1): from an RGB-D frame to the
//! object the grasp is for.
//!
//! - [`rgbd`]: the frame as received ([`RgbdFrame`]: raw `rgb8`/`bgr8` or PNG/JPEG colour,
//!   `16UC1`/`32FC1`/16-bit PNG depth, intrinsics, depth scale, camera-to-world) and its
//!   validated decoding into a [`DecodedFrame`].
//! - [`depth_to_cloud`]: back-projection of the valid depth pixels into a [`PixelCloud`].
//! - [`grasp_type`]: the grasp-type network (ch. 4.2.2, ONNX Runtime): six per-pixel
//!   probability maps, P(s|O) over the object's region (Eq 4.3), the chosen type and the
//!   attention point.
//! - [`saliency`]: the VOCUS2 saliency map (ch. 4.2.1); the most salient object is the default
//!   target.
//! - [`recognition`]: the object by name (§3.2.1): a small CNN says what each segmented object
//!   is, so that `hints.object` can name the target.
//! - [`segmentation`]: support-plane removal, Euclidean clustering and the choice of the target
//!   object (hint pixel, hint box, saliency, image centre).
//! - [`roi`]: mean-shift regions of the saliency map; the ROI.
//! - [`information`]: the whole chain from a decoded frame to Ω = {ROI, grasp type, attention
//!   point}.
//! - [`view_fusion`]: further views of the same object (camera-to-world known) added to the
//!   first view's object points.
//!
//! The picture of a plan for people, drawn over what perception saw, is [`crate::plan_overlay`]:
//! it needs the plan, and perception sits below planning.

pub mod depth_to_cloud;
pub mod grasp_type;
pub mod information;
pub mod recognition;
pub mod rgbd;
pub mod rgbd_wire;
pub mod roi;
pub mod saliency;
pub mod segmentation;
pub mod view_fusion;

pub use depth_to_cloud::{CloudFrame, PixelCloud, back_project, depth_to_cloud};
pub use grasp_type::{
    GraspTypeModel, ModelError, TypeMaps, attention_pixel, bilinear_taps, choose_type,
    resized_planes, type_probabilities,
};
pub use information::{
    GraspInformation, InformationParams, PerceptionModels, PerceptionReport, PerceptionTimings,
    ProbabilityMaps, TypeDetection, grasp_information,
};
pub use recognition::{RecognisedObject, RecognitionModel};
pub use rgbd::{
    CameraIntrinsics, ColorEncoding, DecodedFrame, DepthEncoding, ImageData, RgbdFrame, RgbdLimits,
};
pub use rgbd_wire::{WireImage, camera_pose, sniff_encoding};
pub use roi::{
    RegionParams, SalientRegions, mask_box, region_of_interest, salient_regions,
    salient_regions_near,
};
pub use saliency::{Plane32, SaliencyParams, saliency_map};
pub use segmentation::{
    Cluster, Segmentation, SegmentationParams, TargetChoice, TargetHint, euclidean_clusters,
    objects_on_plane, segment,
};
pub use view_fusion::{FusionReport, fuse_views};
