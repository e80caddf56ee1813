//! Single views of a YCB object on a table, the way a depth camera above a table sees it.

use crate::render::{Camera, TablePatch, crop_corners, render_view};
use crate::sample::downsample_indices;
use crate::ycb::{Object, mesh, mesh_aabb};
use crate::{Result, TestkitError};
use graspd_core::cloud::{Plane, PointCloud};
use nalgebra::{Point3, Vector3};

/// How to take a view. [`ViewSpec::standard`] gives the defaults of [`standard_view`].
#[derive(Debug, Clone, PartialEq)]
pub struct ViewSpec {
    /// Points on the object in the result (exactly, unless the view has fewer even at 8x the
    /// sensor resolution).
    pub n_points: usize,
    /// Seeds the depth noise and the downsampling.
    pub seed: u64,
    /// Camera distance from the object's bounding-box centre, m.
    pub distance: f64,
    /// Camera elevation above the horizontal through the centre, degrees.
    pub elevation_deg: f64,
    /// Camera azimuth about z, degrees (0: on the +x side of the object).
    pub azimuth_deg: f64,
    /// Gaussian range noise, m.
    pub noise_sigma: f64,
    /// `Some(h)`: include the table patch (2h × 2h at z = 0 under the object) in the cloud,
    /// downsampled at the object's rate. `None`: object points only (the table still hides
    /// what lies below z = 0).
    pub table_half_extent: Option<f64>,
}

impl ViewSpec {
    /// 0.6 m away, 40° above the table, azimuth 200° (from the −x side, a little toward −y),
    /// 0.5 mm range noise, no table in the cloud.
    pub fn standard(n_points: usize, seed: u64) -> ViewSpec {
        ViewSpec {
            n_points,
            seed,
            distance: 0.6,
            elevation_deg: 40.0,
            azimuth_deg: 200.0,
            noise_sigma: 0.0005,
            table_half_extent: None,
        }
    }

    /// The same view with a `2 half_extent` square table patch in the cloud.
    pub fn with_table(mut self, half_extent: f64) -> ViewSpec {
        self.table_half_extent = Some(half_extent);
        self
    }
}

/// A single view of an object, in the world frame (metres, z up, the table is z = 0).
#[derive(Debug, Clone)]
pub struct ViewCloud {
    pub object: Object,
    /// The points (object only unless the spec asked for the table); no normals, as from a
    /// depth sensor.
    pub cloud: PointCloud,
    /// The true surface normal at each point, turned toward the camera.
    pub true_normals: Vec<Vector3<f64>>,
    /// Whether each point is on the table (all false without a table).
    pub is_table: Vec<bool>,
    /// Camera position.
    pub viewpoint: Point3<f64>,
    /// The table: z = 0, normal +z.
    pub support_plane: Plane,
    /// Centre of the object's mesh bounding box (the camera looks at it).
    pub object_center: Point3<f64>,
    /// The object's mesh bounding box (min, max).
    pub object_aabb: (Point3<f64>, Point3<f64>),
    /// The (cropped) camera that took the view.
    pub camera: Camera,
}

impl ViewCloud {
    /// The object points only (drops table points, if any).
    pub fn object_cloud(&self) -> PointCloud {
        PointCloud::new(
            self.cloud
                .points
                .iter()
                .zip(&self.is_table)
                .filter(|(_, t)| !**t)
                .map(|(p, _)| *p)
                .collect(),
        )
    }
}

/// The standard single view of `object` (see [`ViewSpec::standard`]) with exactly `n_points`
/// object points, deterministic for `seed`.
///
/// # Panics
/// If the test data cannot be loaded (the message says where it looked; set
/// `GRASPD_TESTDATA`). Use [`view`] for a `Result`.
pub fn standard_view(object: Object, n_points: usize, seed: u64) -> ViewCloud {
    view(object, &ViewSpec::standard(n_points, seed)).unwrap_or_else(|e| panic!("{e}"))
}

/// A view of `object` as `spec` says.
pub fn view(object: Object, spec: &ViewSpec) -> Result<ViewCloud> {
    let mesh = mesh(object)?;
    let (lo, hi) = mesh_aabb(&mesh);
    let center = nalgebra::center(&lo, &hi);
    // A table is always there to hide what pokes below z = 0; it is kept in the cloud only on
    // request.
    let footprint = ((hi.x - lo.x).powi(2) + (hi.y - lo.y).powi(2)).sqrt() / 2.0;
    let table = TablePatch {
        center_x: center.x,
        center_y: center.y,
        half_extent: spec.table_half_extent.unwrap_or(footprint + 0.02),
    };
    let base = Camera::orbit(center, spec.distance, spec.elevation_deg, spec.azimuth_deg)
        .with_noise(spec.noise_sigma, spec.seed ^ 0x0a15_e5ee)
        .with_table(table);
    let corners = crop_corners(&lo, &hi, spec.table_half_extent.is_some().then_some(&table));
    let mut zoom = 1.0;
    let (camera, rendered) = loop {
        let mut cam = base.clone().zoomed(zoom);
        cam.crop_to(&corners, 2.0);
        let r = render_view(&mesh, &cam);
        let on_object = r.is_table.iter().filter(|t| !**t).count();
        if on_object >= spec.n_points || zoom >= 8.0 {
            break (cam, r);
        }
        // Hits grow with the square of the zoom; aim 30 % above the request.
        let want = (1.3 * spec.n_points as f64 / on_object.max(1) as f64).sqrt();
        zoom = (zoom * want.max(1.1)).min(8.0);
    };
    let obj_idx: Vec<usize> = (0..rendered.is_table.len())
        .filter(|&i| !rendered.is_table[i])
        .collect();
    let tab_idx: Vec<usize> = (0..rendered.is_table.len())
        .filter(|&i| rendered.is_table[i])
        .collect();
    if obj_idx.is_empty() {
        return Err(TestkitError(format!(
            "{object}: the view from {} sees nothing of the object",
            rendered.viewpoint
        )));
    }
    let mut keep = vec![false; rendered.is_table.len()];
    for k in downsample_indices(obj_idx.len(), spec.n_points, spec.seed) {
        keep[obj_idx[k]] = true;
    }
    if spec.table_half_extent.is_some() {
        let rate = (spec.n_points as f64 / obj_idx.len() as f64).min(1.0);
        let n_table = (tab_idx.len() as f64 * rate).round() as usize;
        for k in downsample_indices(tab_idx.len(), n_table, spec.seed.wrapping_add(1)) {
            keep[tab_idx[k]] = true;
        }
    }
    let sel: Vec<usize> = (0..keep.len()).filter(|&i| keep[i]).collect();
    Ok(ViewCloud {
        object,
        cloud: PointCloud::new(sel.iter().map(|&i| rendered.cloud.points[i]).collect()),
        true_normals: sel.iter().map(|&i| rendered.normals[i]).collect(),
        is_table: sel.iter().map(|&i| rendered.is_table[i]).collect(),
        viewpoint: rendered.viewpoint,
        support_plane: Plane {
            normal: Vector3::z(),
            offset: 0.0,
        },
        object_center: center,
        object_aabb: (lo, hi),
        camera,
    })
}
