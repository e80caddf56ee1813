//! ROS `sensor_msgs/PointCloud2` as untrusted input, without ROS: the message's layout fields
//! (`height`, `width`, `fields`, `is_bigendian`, `point_step`, `row_step`, `data`,
//! `is_dense`) read into a [`PointCloud`] — what a robot stack holds in its topics, sent as it is.
//!
//! Rules (ROS REP conventions, and the PCD/PLY readers' where ROS leaves a choice):
//! - `x`, `y` and `z` are required, each one element (`count` 0 is read as 1, as rosbag
//!   writers leave it), of any of the eight datatypes; `normal_x`/`normal_y`/`normal_z` (or
//!   `nx`/`ny`/`nz`) are read when all three are present. Other fields (`rgb`, `intensity`,
//!   `ring`, padding) are skipped by their offsets.
//! - The cloud is `height` rows of `width` points (organised: a camera's image grid; unorganised:
//!   height 1), point `j` of row `i` at byte `i·row_step + j·point_step`; rows may be padded
//!   (`row_step ≥ width·point_step`) and points too (`point_step` beyond the last field).
//! - `data` holds exactly `height·row_step` bytes.
//! - Points whose x, y or z is NaN are skipped (`is_dense = false` clouds mark invalid pixels
//!   so; a driver that sets `is_dense` wrongly loses nothing); infinities are kept for
//!   [`PointCloud::validate`]. Normals follow the file readers' rule (module `io`).
//!
//! Every number is checked against the bytes present before anything is allocated; errors are
//! [`FieldError`]s naming the message's field under the request's name for it (`cloud2.…`).

use super::{CloudBuilder, Slot};
use crate::cloud::PointCloud;
use crate::error::FieldError;

/// `sensor_msgs/PointField` datatypes.
pub const INT8: u32 = 1;
pub const UINT8: u32 = 2;
pub const INT16: u32 = 3;
pub const UINT16: u32 = 4;
pub const INT32: u32 = 5;
pub const UINT32: u32 = 6;
pub const FLOAT32: u32 = 7;
pub const FLOAT64: u32 = 8;

/// One `sensor_msgs/PointField`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PointField {
    pub name: String,
    /// Byte offset of the field in a point.
    pub offset: u32,
    /// One of [`INT8`] … [`FLOAT64`].
    pub datatype: u32,
    /// Elements in the field (1 for x, y, z).
    pub count: u32,
}

/// The layout of a `sensor_msgs/PointCloud2` (its bytes travel beside it).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct PointCloud2Layout {
    pub height: u32,
    pub width: u32,
    pub fields: Vec<PointField>,
    pub is_bigendian: bool,
    pub point_step: u32,
    pub row_step: u32,
    pub is_dense: bool,
}

/// Bytes of one element of a datatype; None for an unknown one.
pub fn datatype_size(datatype: u32) -> Option<usize> {
    Some(match datatype {
        INT8 | UINT8 => 1,
        INT16 | UINT16 => 2,
        INT32 | UINT32 | FLOAT32 => 4,
        FLOAT64 => 8,
        _ => return None,
    })
}

impl PointCloud2Layout {
    /// Points the layout claims (width × height), None on overflow.
    pub fn points(&self) -> Option<u64> {
        u64::from(self.width).checked_mul(u64::from(self.height))
    }

    /// The float32 layout the writer uses: x, y, z and, with `normals`, normal_x/y/z, packed,
    /// little-endian, one row.
    pub fn packed_f32(points: usize, normals: bool) -> Self {
        let names: &[&str] = if normals {
            &["x", "y", "z", "normal_x", "normal_y", "normal_z"]
        } else {
            &["x", "y", "z"]
        };
        let point_step = 4 * names.len() as u32;
        let width = u32::try_from(points).unwrap_or(u32::MAX);
        Self {
            height: 1,
            width,
            fields: names
                .iter()
                .enumerate()
                .map(|(i, n)| PointField {
                    name: (*n).to_string(),
                    offset: 4 * i as u32,
                    datatype: FLOAT32,
                    count: 1,
                })
                .collect(),
            is_bigendian: false,
            point_step,
            row_step: point_step.saturating_mul(width),
            is_dense: true,
        }
    }
}

/// Where each of x, y, z (and the normal components) sits in a point: offset and datatype.
type Slots = [Option<(usize, u32)>; 6];

/// Reads a PointCloud2's points (module rules). `field` is the request's name for the message
/// (`cloud2`), prefixed to every error's field.
pub fn read_pointcloud2(
    layout: &PointCloud2Layout,
    data: &[u8],
    field: &str,
) -> Result<PointCloud, FieldError> {
    let err = |name: &str, message: String| FieldError::new(format!("{field}.{name}"), message);
    let slots = slots(layout, &err)?;
    let point_step = layout.point_step as usize;
    let row_step = layout.row_step as usize;
    let (width, height) = (layout.width as usize, layout.height as usize);
    let row_bytes = width.checked_mul(point_step).filter(|&b| b <= row_step);
    if row_bytes.is_none() {
        return Err(err(
            "row_step",
            format!(
                "{} is less than width {} × point_step {}",
                layout.row_step, layout.width, layout.point_step
            ),
        ));
    }
    let total = height.checked_mul(row_step);
    if total != Some(data.len()) {
        return Err(err(
            "data",
            format!(
                "holds {} bytes; height {} × row_step {} asks for {}",
                data.len(),
                layout.height,
                layout.row_step,
                total.map_or("more than this machine can address".into(), |t| t
                    .to_string())
            ),
        ));
    }
    let with_normals = slots[3].is_some();
    // width × height ≤ data.len() / point_step here (point_step ≥ 1 once a field fits).
    let mut out = CloudBuilder::new(width * height, with_normals);
    let mut v = [0.0f64; 6];
    for row in data.chunks_exact(row_step.max(1)).take(height) {
        for point in row.chunks_exact(point_step).take(width) {
            for (k, slot) in slots.iter().enumerate() {
                if let Some((offset, datatype)) = slot {
                    v[k] = read_scalar(point, *offset, *datatype, layout.is_bigendian);
                }
            }
            out.push(&v);
        }
    }
    Ok(out.finish())
}

/// Checks the fields and finds x, y, z and the normals (module rules).
fn slots(
    layout: &PointCloud2Layout,
    err: &impl Fn(&str, String) -> FieldError,
) -> Result<Slots, FieldError> {
    let mut found: Slots = [None; 6];
    let mut names: Vec<&str> = Vec::with_capacity(layout.fields.len());
    for (i, f) in layout.fields.iter().enumerate() {
        let at = |what: &str| format!("fields[{i}].{what}");
        if names.contains(&f.name.as_str()) {
            return Err(err(
                &at("name"),
                format!("field {:?} is given twice", f.name),
            ));
        }
        names.push(&f.name);
        let size = datatype_size(f.datatype).ok_or_else(|| {
            err(
                &at("datatype"),
                format!(
                    "{} is not a PointField datatype (1 INT8 … 8 FLOAT64)",
                    f.datatype
                ),
            )
        })?;
        let count = f.count.max(1) as u64;
        let end = u64::from(f.offset) + size as u64 * count;
        if end > u64::from(layout.point_step) {
            return Err(err(
                "point_step",
                format!(
                    "{} is too small: field {:?} ends at byte {end} of a point",
                    layout.point_step, f.name
                ),
            ));
        }
        if let Some(slot) = Slot::of(&f.name) {
            if count != 1 {
                return Err(err(
                    &at("count"),
                    format!("field {:?} must have one element, not {count}", f.name),
                ));
            }
            found[slot.index()] = Some((f.offset as usize, f.datatype));
        }
    }
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        if found[k].is_none() {
            return Err(err(
                "fields",
                format!(
                    "no field {name:?}: a cloud needs x, y and z (fields given: {})",
                    names.join(", ")
                ),
            ));
        }
    }
    match found[3..].iter().filter(|s| s.is_some()).count() {
        0 | 3 => Ok(found),
        _ => Err(err(
            "fields",
            "only some normal components are present; give all three of normal_x/normal_y/\
             normal_z (or nx/ny/nz) or none"
                .into(),
        )),
    }
}

/// One element at `offset` of `point` (in bounds: checked against point_step by [`slots`]).
fn read_scalar(point: &[u8], offset: usize, datatype: u32, big_endian: bool) -> f64 {
    let size = datatype_size(datatype).unwrap_or(1);
    let mut b = [0u8; 8];
    b[..size].copy_from_slice(&point[offset..offset + size]);
    if big_endian {
        b[..size].reverse();
    }
    match datatype {
        INT8 => b[0] as i8 as f64,
        UINT8 => b[0] as f64,
        INT16 => i16::from_le_bytes([b[0], b[1]]) as f64,
        UINT16 => u16::from_le_bytes([b[0], b[1]]) as f64,
        INT32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        UINT32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        FLOAT32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        _ => f64::from_le_bytes(b),
    }
}

/// Writes a cloud as a one-row, little-endian float32 PointCloud2 (x, y, z and the normals when
/// the cloud has them): the layout and its bytes (clients, tests, fixtures).
pub fn write_pointcloud2(cloud: &PointCloud) -> (PointCloud2Layout, Vec<u8>) {
    let normals = cloud.normals.as_ref();
    let layout = PointCloud2Layout::packed_f32(cloud.points.len(), normals.is_some());
    let mut data = Vec::with_capacity(layout.row_step as usize);
    for (i, p) in cloud.points.iter().enumerate() {
        let n = normals.map(|n| n[i]);
        for v in p.coords.iter().chain(n.iter().flat_map(|n| n.iter())) {
            data.extend_from_slice(&(*v as f32).to_le_bytes());
        }
    }
    (layout, data)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Point3, Vector3};

    fn field(name: &str, offset: u32, datatype: u32) -> PointField {
        PointField {
            name: name.into(),
            offset,
            datatype,
            count: 1,
        }
    }

    /// A 2 × 3 organised cloud, big-endian float64 x, y, z after a 4-byte intensity, 4 bytes of
    /// point padding and 8 bytes of row padding; one NaN pixel.
    #[test]
    fn organised_big_endian_padded_cloud_skips_nan_pixels() {
        let layout = PointCloud2Layout {
            height: 2,
            width: 3,
            fields: vec![
                field("intensity", 0, FLOAT32),
                field("x", 4, FLOAT64),
                field("y", 12, FLOAT64),
                field("z", 20, FLOAT64),
            ],
            is_bigendian: true,
            point_step: 32,
            row_step: 3 * 32 + 8,
            is_dense: false,
        };
        let mut data = Vec::new();
        for i in 0..2 {
            for j in 0..3 {
                data.extend_from_slice(&7.5f32.to_be_bytes());
                let x = if (i, j) == (1, 1) { f64::NAN } else { j as f64 };
                for v in [x, i as f64, 0.5 + 0.25 * (i * 3 + j) as f64] {
                    data.extend_from_slice(&v.to_be_bytes());
                }
                data.extend_from_slice(&[0xAB; 4]);
            }
            data.extend_from_slice(&[0xCD; 8]);
        }
        let c = read_pointcloud2(&layout, &data, "cloud2").unwrap();
        assert_eq!(c.points.len(), 5);
        assert_eq!(c.points[0], Point3::new(0.0, 0.0, 0.5));
        assert_eq!(c.points[2], Point3::new(2.0, 0.0, 1.0));
        // Row 1's middle pixel is skipped: the fifth point read is row 1, column 2.
        assert_eq!(c.points[4], Point3::new(2.0, 1.0, 1.75));
        assert!(c.normals.is_none());
    }

    /// The writer's layout reads back, normals included, and integer datatypes read as numbers.
    #[test]
    fn written_cloud_reads_back_and_integer_fields_read() {
        let cloud = PointCloud {
            points: vec![Point3::new(0.1, -0.2, 0.3), Point3::new(1.0, 2.0, 3.0)],
            normals: Some(vec![Vector3::z(), Vector3::x()]),
        };
        let (layout, data) = write_pointcloud2(&cloud);
        assert_eq!((layout.point_step, layout.row_step), (24, 48));
        let back = read_pointcloud2(&layout, &data, "cloud2").unwrap();
        for (a, b) in back.points.iter().zip(&cloud.points) {
            assert!((a - b).norm() < 1e-6);
        }
        assert_eq!(back.normals.unwrap(), vec![Vector3::z(), Vector3::x()]);

        let layout = PointCloud2Layout {
            height: 1,
            width: 1,
            fields: vec![
                field("x", 0, INT16),
                field("y", 2, UINT8),
                field("z", 3, INT8),
            ],
            is_bigendian: false,
            point_step: 4,
            row_step: 4,
            is_dense: true,
        };
        let data = [0xFE, 0xFF, 200, 0x80];
        let c = read_pointcloud2(&layout, &data, "cloud2").unwrap();
        assert_eq!(c.points[0], Point3::new(-2.0, 200.0, -128.0));
    }

    fn bad(layout: &PointCloud2Layout, data: &[u8]) -> FieldError {
        read_pointcloud2(layout, data, "cloud2").unwrap_err()
    }

    /// Each bad layout is refused naming the field that is wrong.
    #[test]
    fn bad_layouts_name_the_field() {
        let good = PointCloud2Layout::packed_f32(2, false);
        let data = vec![0u8; 24];
        assert!(read_pointcloud2(&good, &data, "cloud2").is_ok());

        let mut no_z = good.clone();
        no_z.fields.pop();
        let e = bad(&no_z, &data);
        assert_eq!(e.field, "cloud2.fields");
        assert!(e.message.contains("\"z\""), "{e}");

        let mut short_step = good.clone();
        short_step.point_step = 8;
        short_step.row_step = 16;
        assert_eq!(bad(&short_step, &data[..16]).field, "cloud2.point_step");

        let mut short_row = good.clone();
        short_row.row_step = 20;
        assert_eq!(bad(&short_row, &data).field, "cloud2.row_step");

        assert_eq!(bad(&good, &data[..20]).field, "cloud2.data");
        let mut tall = good.clone();
        tall.height = 2;
        assert_eq!(bad(&tall, &data).field, "cloud2.data");
        let mut huge = good.clone();
        huge.height = u32::MAX;
        huge.row_step = u32::MAX;
        assert_eq!(bad(&huge, &data).field, "cloud2.data");

        let mut unknown = good.clone();
        unknown.fields[1].datatype = 9;
        assert_eq!(bad(&unknown, &data).field, "cloud2.fields[1].datatype");

        let mut twice = good.clone();
        twice.fields[2].name = "x".into();
        assert_eq!(bad(&twice, &data).field, "cloud2.fields[2].name");

        let mut vector = good.clone();
        vector.fields[2].count = 3;
        assert_eq!(bad(&vector, &data).field, "cloud2.point_step");
        vector.point_step = 20;
        vector.row_step = 40;
        assert_eq!(bad(&vector, &[0u8; 40]).field, "cloud2.fields[2].count");

        let mut some_normals = good.clone();
        some_normals.fields.push(field("normal_x", 8, FLOAT32));
        some_normals.point_step = 12;
        assert_eq!(bad(&some_normals, &data).field, "cloud2.fields");
    }
}
