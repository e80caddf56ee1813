//! The point cloud as the planner takes it, and the decoding of the packed form that both
//! transports carry (little-endian float32 x, y, z triples).

use crate::error::FieldError;
use nalgebra::{Point3, Vector3};

/// A cloud in metres, with optional unit normals (one per point).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PointCloud {
    pub points: Vec<Point3<f64>>,
    pub normals: Option<Vec<Vector3<f64>>>,
}

/// Fewest points the planner works with: k-NN normals need a neighbourhood, and an opposition
/// needs candidates on two sides of the object.
pub const MIN_POINTS: usize = 32;

impl PointCloud {
    pub fn new(points: Vec<Point3<f64>>) -> Self {
        Self {
            points,
            normals: None,
        }
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Checks the cloud as untrusted input: non-empty, finite, within `max_points`, normals (if
    /// any) one per point, finite and non-zero (they are normalised here). `field` names the
    /// cloud in errors (e.g. `cloud`).
    pub fn validate(&mut self, field: &str, max_points: usize) -> Result<(), FieldError> {
        if self.points.is_empty() {
            return Err(FieldError::new(field, "the cloud is empty"));
        }
        if self.points.len() > max_points {
            return Err(FieldError::new(
                field,
                format!(
                    "{} points exceed the configured limit of {max_points}",
                    self.points.len()
                ),
            ));
        }
        if let Some(i) = self
            .points
            .iter()
            .position(|p| !p.coords.iter().all(|v| v.is_finite()))
        {
            return Err(FieldError::new(
                format!("{field}.points[{i}]"),
                "coordinate is NaN or infinite",
            ));
        }
        if let Some(i) = self
            .points
            .iter()
            .position(|p| p.coords.iter().any(|v| v.abs() > 1.0e3))
        {
            return Err(FieldError::new(
                format!("{field}.points[{i}]"),
                "coordinate beyond ±1000 m; the cloud must be in metres",
            ));
        }
        if let Some(normals) = &mut self.normals {
            if normals.len() != self.points.len() {
                return Err(FieldError::new(
                    format!("{field}.normals"),
                    format!(
                        "{} normals for {} points; give one per point or none",
                        normals.len(),
                        self.points.len()
                    ),
                ));
            }
            for (i, n) in normals.iter_mut().enumerate() {
                let len = n.norm();
                if !len.is_finite() || len < 1e-9 {
                    return Err(FieldError::new(
                        format!("{field}.normals[{i}]"),
                        "normal is zero, NaN or infinite",
                    ));
                }
                *n /= len;
            }
        }
        if self.points.len() < MIN_POINTS {
            return Err(FieldError::new(
                field,
                format!(
                    "{} points; the planner needs at least {MIN_POINTS}",
                    self.points.len()
                ),
            ));
        }
        Ok(())
    }

    /// Centroid of the points (zero for an empty cloud).
    pub fn centroid(&self) -> Point3<f64> {
        centroid(&self.points)
    }
}

/// Mean of a set of points (origin for none).
pub fn centroid(points: &[Point3<f64>]) -> Point3<f64> {
    if points.is_empty() {
        return Point3::origin();
    }
    let sum = points
        .iter()
        .fold(Vector3::zeros(), |acc, p| acc + p.coords);
    Point3::from(sum / points.len() as f64)
}

/// Decodes packed little-endian float32 triples (x, y, z, …). The error names `field`.
pub fn decode_packed_xyz(bytes: &[u8], field: &str) -> Result<Vec<Point3<f64>>, FieldError> {
    decode_packed_vec3(bytes, field).map(|v| v.into_iter().map(Point3::from).collect())
}

/// Decodes packed little-endian float32 triples as vectors (used for normals).
pub fn decode_packed_vec3(bytes: &[u8], field: &str) -> Result<Vec<Vector3<f64>>, FieldError> {
    if !bytes.len().is_multiple_of(12) {
        return Err(FieldError::new(
            field,
            format!(
                "byte length {} is not a multiple of 12 (three little-endian float32 per point)",
                bytes.len()
            ),
        ));
    }
    Ok(bytes
        .chunks_exact(12)
        .map(|c| {
            let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]) as f64;
            Vector3::new(f(0), f(4), f(8))
        })
        .collect())
}

/// Encodes points as packed little-endian float32 triples (clients, tests, fixtures).
pub fn encode_packed_xyz(points: &[Point3<f64>]) -> Vec<u8> {
    let mut out = Vec::with_capacity(points.len() * 12);
    for p in points {
        for v in p.coords.iter() {
            out.extend_from_slice(&(*v as f32).to_le_bytes());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize) -> Vec<Point3<f64>> {
        (0..n)
            .map(|i| Point3::new(i as f64 * 0.01, (i % 7) as f64 * 0.01, 0.0))
            .collect()
    }

    #[test]
    fn packed_round_trip_and_bad_length() {
        let pts = grid(40);
        let bytes = encode_packed_xyz(&pts);
        assert_eq!(bytes.len(), 480);
        let back = decode_packed_xyz(&bytes, "cloud.points").unwrap();
        for (a, b) in pts.iter().zip(&back) {
            assert!((a - b).norm() < 1e-6);
        }
        let e = decode_packed_xyz(&bytes[..13], "cloud.points").unwrap_err();
        assert_eq!(e.field, "cloud.points");
        assert!(e.message.contains("multiple of 12"));
    }

    #[test]
    fn validation_names_the_problem() {
        let mut empty = PointCloud::default();
        assert!(
            empty
                .validate("cloud", 10)
                .unwrap_err()
                .message
                .contains("empty")
        );
        let mut few = PointCloud::new(grid(5));
        assert!(
            few.validate("cloud", 100)
                .unwrap_err()
                .message
                .contains("at least")
        );
        let mut many = PointCloud::new(grid(50));
        assert!(
            many.validate("cloud", 40)
                .unwrap_err()
                .message
                .contains("limit")
        );
        let mut nan = PointCloud::new(grid(50));
        nan.points[7].y = f64::NAN;
        assert_eq!(
            nan.validate("cloud", 100).unwrap_err().field,
            "cloud.points[7]"
        );
        let mut inf = PointCloud::new(grid(50));
        inf.points[3].x = f64::INFINITY;
        assert_eq!(
            inf.validate("cloud", 100).unwrap_err().field,
            "cloud.points[3]"
        );
        let mut ok = PointCloud::new(grid(50));
        ok.normals = Some(vec![Vector3::new(0.0, 0.0, 2.0); 50]);
        ok.validate("cloud", 100).unwrap();
        assert!((ok.normals.as_ref().unwrap()[0].norm() - 1.0).abs() < 1e-12);
        let mut badn = PointCloud::new(grid(50));
        badn.normals = Some(vec![Vector3::zeros(); 50]);
        assert_eq!(
            badn.validate("cloud", 100).unwrap_err().field,
            "cloud.normals[0]"
        );
    }
}
