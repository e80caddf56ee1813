//! Principal component analysis of small point sets: the one covariance routine behind normals,
//! plane fits, object axes and grasp-polygon areas. The 3×3 symmetric eigenproblem is solved in
//! closed form (Eberly's robust solver, via glamx/parry), which is several times faster than an
//! iterative one on the planner's hot path.

use nalgebra::{Matrix3, Point3, Vector3};
use parry3d_f64::math::{Mat3, SymmetricEigen3, Vector as PVec};

/// Mean and (unnormalised) covariance Σ (p − mean)(p − mean)ᵀ of the selected points.
pub fn covariance<I>(points: &[Point3<f64>], selection: I) -> (Point3<f64>, Matrix3<f64>)
where
    I: IntoIterator<Item = usize> + Clone,
{
    let mut n = 0usize;
    let mut sum = Vector3::zeros();
    for i in selection.clone() {
        sum += points[i].coords;
        n += 1;
    }
    let mean = sum / n.max(1) as f64;
    let mut cov = Matrix3::zeros();
    for i in selection {
        let d = points[i].coords - mean;
        cov += d * d.transpose();
    }
    (Point3::from(mean), cov)
}

/// Eigenvalues (ascending) and unit eigenvectors of a symmetric 3×3 matrix.
pub fn eigen(cov: &Matrix3<f64>) -> ([f64; 3], [Vector3<f64>; 3]) {
    let col = |j: usize| PVec::new(cov[(0, j)], cov[(1, j)], cov[(2, j)]);
    let e = SymmetricEigen3::new(Mat3::from_cols(col(0), col(1), col(2)));
    let v = |c: PVec| {
        let v = Vector3::new(c.x, c.y, c.z);
        v.try_normalize(1e-300).unwrap_or_else(Vector3::z)
    };
    (
        [e.eigenvalues.x, e.eigenvalues.y, e.eigenvalues.z],
        [
            v(e.eigenvectors.x_axis),
            v(e.eigenvectors.y_axis),
            v(e.eigenvectors.z_axis),
        ],
    )
}

/// Unit eigenvector of the smallest eigenvalue: the normal of a best-fit plane.
pub fn smallest_axis(cov: &Matrix3<f64>) -> Vector3<f64> {
    let v = eigen(cov).1[0];
    if v.iter().all(|x| x.is_finite()) {
        v
    } else {
        Vector3::z()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_normal_and_axes() {
        let pts: Vec<Point3<f64>> = (0..50)
            .map(|i| Point3::new((i % 10) as f64 * 0.02, (i / 10) as f64 * 0.01, 0.3))
            .collect();
        let (mean, cov) = covariance(&pts, 0..pts.len());
        assert!((mean.z - 0.3).abs() < 1e-12);
        assert!(smallest_axis(&cov).z.abs() > 0.999999);
        let (vals, vecs) = eigen(&cov);
        assert!(vals[0] <= vals[1] && vals[1] <= vals[2]);
        assert!(
            vecs[2].x.abs() > 0.999,
            "longest axis along x: {:?}",
            vecs[2]
        );
    }
}
