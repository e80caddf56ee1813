//! Positions (`{x, y, z}` or `[x, y, z]`), quaternions, poses, planes and pixel regions.

use crate::schemas::Vec3InputDoc;
use graspd_core::cloud::Plane;
use graspd_core::planning::Pose;
use nalgebra::{Point3, Vector3};
use serde::de::{self, IgnoredAny, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};
use std::fmt;
use utoipa::ToSchema;

/// A 3-D point or vector: written as `{x, y, z}`, read from that or from `[x, y, z]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct Vec3Json {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

impl From<&Point3<f64>> for Vec3Json {
    fn from(p: &Point3<f64>) -> Self {
        Self {
            x: p.x,
            y: p.y,
            z: p.z,
        }
    }
}

impl From<&Vector3<f64>> for Vec3Json {
    fn from(v: &Vector3<f64>) -> Self {
        Self {
            x: v.x,
            y: v.y,
            z: v.z,
        }
    }
}

impl Vec3Json {
    pub fn point(&self) -> Point3<f64> {
        Point3::new(self.x, self.y, self.z)
    }

    pub fn vector(&self) -> Vector3<f64> {
        Vector3::new(self.x, self.y, self.z)
    }
}

impl<'de> Deserialize<'de> for Vec3Json {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Vec3Json;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("[x, y, z] or {\"x\": .., \"y\": .., \"z\": ..}")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut s: A) -> Result<Vec3Json, A::Error> {
                let mut v = [0.0; 3];
                for (i, slot) in v.iter_mut().enumerate() {
                    *slot = s
                        .next_element()?
                        .ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                if s.next_element::<IgnoredAny>()?.is_some() {
                    return Err(de::Error::invalid_length(4, &self));
                }
                Ok(Vec3Json {
                    x: v[0],
                    y: v[1],
                    z: v[2],
                })
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<Vec3Json, A::Error> {
                let mut v = [None; 3];
                while let Some(key) = m.next_key::<String>()? {
                    let i = match key.as_str() {
                        "x" => 0,
                        "y" => 1,
                        "z" => 2,
                        other => return Err(de::Error::unknown_field(other, &["x", "y", "z"])),
                    };
                    v[i] = Some(m.next_value()?);
                }
                let get =
                    |i: usize, n: &'static str| v[i].ok_or_else(|| de::Error::missing_field(n));
                Ok(Vec3Json {
                    x: get(0, "x")?,
                    y: get(1, "y")?,
                    z: get(2, "z")?,
                })
            }
        }
        d.deserialize_any(V)
    }
}

/// A rotation as a unit quaternion (x, y, z, w).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct QuaternionJson {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct PoseJson {
    #[schema(value_type = Vec3InputDoc)]
    pub position: Vec3Json,
    pub orientation: QuaternionJson,
}

impl From<&Pose> for PoseJson {
    fn from(p: &Pose) -> Self {
        let q = p.orientation;
        Self {
            position: (&p.position).into(),
            orientation: QuaternionJson {
                x: q.i,
                y: q.j,
                z: q.k,
                w: q.w,
            },
        }
    }
}

/// The plane n·x + offset = 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct PlaneJson {
    #[schema(value_type = Vec3InputDoc)]
    pub normal: Vec3Json,
    pub offset: f64,
}

impl From<&Plane> for PlaneJson {
    fn from(p: &Plane) -> Self {
        Self {
            normal: (&p.normal).into(),
            offset: p.offset,
        }
    }
}

/// A box in image pixels, [u_min, u_max) × [v_min, v_max).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct RegionJson {
    pub u_min: u32,
    pub v_min: u32,
    pub u_max: u32,
    pub v_max: u32,
}
