//! Perception (method.md §4, dissertation ch. 4.2 and 5.3.1): from an RGB-D frame to the
//! object the grasp is for.
//!
//! - [`rgbd`]: the frame as received ([`RgbdFrame`]: raw `rgb8`/`bgr8` or PNG/JPEG colour,
//!   `16UC1`/`32FC1`/16-bit PNG depth, intrinsics, depth scale, camera-to-world) and its
//!   validated decoding into a [`DecodedFrame`].
//! - [`depth_to_cloud`]: back-projection of the valid depth pixels into a [`PixelCloud`].
//! - [`saliency`]: the VOCUS2 saliency map (ch. 4.2.1); the most salient object is the default
//!   target.
//! - [`segmentation`]: support-plane removal, Euclidean clustering and the choice of the target
//!   object (hint pixel, hint box, saliency, image centre).

pub mod depth_to_cloud;
pub mod rgbd;
pub mod saliency;
pub mod segmentation;

pub use depth_to_cloud::{CloudFrame, PixelCloud, back_project, depth_to_cloud};
pub use rgbd::{
    CameraIntrinsics, ColorEncoding, DecodedFrame, DepthEncoding, ImageData, RgbdFrame, RgbdLimits,
};
pub use saliency::{Plane32, SaliencyParams, saliency_map};
pub use segmentation::{
    Cluster, Segmentation, SegmentationParams, TargetChoice, TargetHint, euclidean_clusters,
    segment,
};
