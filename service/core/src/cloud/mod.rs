//! Point clouds: the cloud type, k-NN normals, the support plane, and file formats.

pub mod centreline;
pub mod completion;
pub mod io;
pub mod normals;
pub mod pca;
pub mod plane;
pub mod point_cloud;

pub use completion::{Completion, Symmetry, symmetric_completion};
pub use normals::{
    CloudIndex, LazyNormals, Orientation, estimate_normals, knn_lists, normals_from_neighbours,
};
pub use plane::{Plane, RansacParams, detect_support_plane, tangents};
pub use point_cloud::{
    MIN_POINTS, PointCloud, decode_packed_vec3, decode_packed_xyz, encode_packed_xyz,
};
