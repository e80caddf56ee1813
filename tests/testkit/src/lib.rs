//! Realistic point clouds of the YCB test objects for graspd's tests, benchmarks and examples.
//!
//! - [`ycb`]: the 13 objects in `<workspace>/../shared/testdata/objects/ycb` (or
//!   `$GRASPD_TESTDATA/objects/ycb`) and their meshes as parry [`TriMesh`]es, in metres, z up,
//!   standing on the table plane z = 0 (origin not centred: see the objects README).
//! - [`render`]: a pinhole depth sensor that ray-casts a mesh (and optionally a finite table
//!   patch at z = 0) and returns a single-view cloud in the world frame.
//! - [`rgbd`]: RGB-D frames (colour, depth, ground-truth labels) of objects on a table, for
//!   the perception tests.
//! - [`sample`]: seeded downsampling and whole-surface sampling with outward normals.
//! - [`view`]: [`standard_view`], the one call most tests use.
//!
//! ```no_run
//! use graspd_testkit::{standard_view, ycb::Object};
//! let v = standard_view(Object::TomatoSoupCan, 2000, 1);
//! assert_eq!(v.cloud.len(), 2000);
//! ```

pub mod npy;
pub mod render;
pub mod rgbd;
pub mod sample;
pub mod texture;
pub mod view;
pub mod ycb;

pub use parry3d_f64::shape::TriMesh;
pub use render::{Camera, Intrinsics, RenderedView, TablePatch, render_view};
pub use sample::{downsample_indices, downsample_to, sample_surface};
pub use view::{ViewCloud, ViewSpec, standard_view, view};
pub use ycb::{Object, load_mesh, mesh};

use std::fmt;
use std::path::PathBuf;

/// Errors of the testkit (missing test data, unreadable meshes).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TestkitError(pub String);

impl fmt::Display for TestkitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for TestkitError {}

pub type Result<T> = std::result::Result<T, TestkitError>;

/// The workspace root (`tests/testkit/../..`).
pub fn workspace_root() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

/// The shared test data: `$GRASPD_TESTDATA` if set, else `<workspace>/../shared/testdata`.
pub fn testdata_dir() -> PathBuf {
    match std::env::var_os("GRASPD_TESTDATA") {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => workspace_root().join("../shared/testdata"),
    }
}

/// The materials of the real BioTac slides (`tactile/biotac_slide`) with the class the data's
/// README groups them in (its "Material classes" table: the four classes of Eq 6.4).
pub const BIOTAC_SLIDE_MATERIALS: [(&str, &str); 10] = [
    ("mat5", "plastic"),
    ("mat8", "paper"),
    ("mat9", "plastic"),
    ("mat10", "plastic"),
    ("mat13", "plastic"),
    ("mat14", "paper"),
    ("mat17", "foam"),
    ("mat18", "foam"),
    ("mat19", "foam"),
    ("mat20", "metal"),
];

/// The real BioTac slides: `$GRASPD_TACTILE_DATA`, else `tactile/biotac_slide` of
/// [`testdata_dir`]; `None` when the folder does not exist (tests then skip with a note).
pub fn biotac_slide_dir() -> Option<PathBuf> {
    let p = std::env::var_os("GRASPD_TACTILE_DATA")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .unwrap_or_else(|| testdata_dir().join("tactile/biotac_slide"));
    p.is_dir().then_some(p)
}
