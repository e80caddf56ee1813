//! Seeded downsampling and surface sampling.

use crate::ycb::signed_volume;
use graspd_core::cloud::PointCloud;
use nalgebra::{Point3, Vector3};
use parry3d_f64::shape::TriMesh;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `min(n, len)` distinct indices of `0..len`, chosen uniformly at random for `seed`, in
/// increasing order (so a scan-line cloud keeps its order).
pub fn downsample_indices(len: usize, n: usize, seed: u64) -> Vec<usize> {
    if n >= len {
        return (0..len).collect();
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xd0_5a_4d_1e);
    let mut idx = rand::seq::index::sample(&mut rng, len, n).into_vec();
    idx.sort_unstable();
    idx
}

/// Exactly `min(n, cloud.len())` points of `cloud` (with their normals, if any), chosen
/// uniformly at random for `seed`, in their original order.
pub fn downsample_to(cloud: &PointCloud, n: usize, seed: u64) -> PointCloud {
    let idx = downsample_indices(cloud.len(), n, seed);
    PointCloud {
        points: idx.iter().map(|&i| cloud.points[i]).collect(),
        normals: cloud
            .normals
            .as_ref()
            .map(|ns| idx.iter().map(|&i| ns[i]).collect()),
    }
}

/// `n` points spread uniformly (by area) over the whole surface of `mesh`, with the outward
/// face normal of each (the mesh's winding decides "outward"; a mesh wound inside-out, with a
/// negative signed volume, has its normals flipped). Deterministic for `seed`.
pub fn sample_surface(mesh: &TriMesh, n: usize, seed: u64) -> PointCloud {
    let v = mesh.vertices();
    let p = |i: u32| {
        let q = v[i as usize];
        Point3::new(q.x, q.y, q.z)
    };
    let flip = if signed_volume(mesh) < 0.0 { -1.0 } else { 1.0 };
    // (corner, edge 1, edge 2, outward normal scaled by twice the area)
    type Tri = (Point3<f64>, Vector3<f64>, Vector3<f64>, Vector3<f64>);
    let tris: Vec<Tri> = mesh
        .indices()
        .iter()
        .map(|t| {
            let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
            let (e1, e2) = (b - a, c - a);
            (a, e1, e2, e1.cross(&e2) * flip)
        })
        .collect();
    // Cumulative areas (twice the area; the factor cancels).
    let mut cum = Vec::with_capacity(tris.len());
    let mut total = 0.0;
    for t in &tris {
        total += t.3.norm();
        cum.push(total);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5a_3f_ac_e5);
    let mut points = Vec::with_capacity(n);
    let mut normals = Vec::with_capacity(n);
    if total <= 0.0 {
        return PointCloud::default();
    }
    for _ in 0..n {
        let x = rng.random::<f64>() * total;
        let k = cum.partition_point(|&c| c <= x).min(tris.len() - 1);
        let (a, e1, e2, nrm) = &tris[k];
        let (mut s, mut t) = (rng.random::<f64>(), rng.random::<f64>());
        if s + t > 1.0 {
            s = 1.0 - s;
            t = 1.0 - t;
        }
        points.push(a + e1 * s + e2 * t);
        normals.push(nrm.normalize());
    }
    PointCloud {
        points,
        normals: Some(normals),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn downsample_is_exact_ordered_and_seeded() {
        let cloud = PointCloud {
            points: (0..1000).map(|i| Point3::new(i as f64, 0.0, 0.0)).collect(),
            normals: Some(vec![Vector3::z(); 1000]),
        };
        let a = downsample_to(&cloud, 100, 7);
        assert_eq!(a.len(), 100);
        assert_eq!(a.normals.as_ref().unwrap().len(), 100);
        assert!(a.points.windows(2).all(|w| w[0].x < w[1].x));
        assert_eq!(a, downsample_to(&cloud, 100, 7));
        assert_ne!(a, downsample_to(&cloud, 100, 8));
        assert_eq!(downsample_to(&cloud, 5000, 1).len(), 1000);
    }
}
