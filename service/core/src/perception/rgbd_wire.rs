//! The RGB-D frame as the transports receive it (ROS `sensor_msgs/Image` and `CameraInfo`
//! fields): declared sizes or those a PNG / JPEG header gives, encoding names, big-endian raw
//! depth made little-endian, the intrinsics as fx, fy, cx, cy or `CameraInfo.K`, and the camera
//! pose — checked and turned into an [`RgbdFrame`], whose pixels [`RgbdFrame::decode`] reads.

use super::rgbd::{CameraIntrinsics, ColorEncoding, DepthEncoding, ImageData, RgbdFrame};
use crate::error::FieldError;
use image::ImageReader;
use nalgebra::{Isometry3, Point3, Quaternion, UnitQuaternion};
use std::io::Cursor;

impl CameraIntrinsics {
    /// The intrinsics as sent: fx, fy, cx, cy, or ROS `CameraInfo.K` (`k`, 3 × 3 row-major:
    /// fx 0 cx / 0 fy cy / 0 0 1), or both when they agree. A K with skew or a last row other
    /// than 0 0 1 is not a pinhole graspd can use and is refused; so is a K that disagrees
    /// with a focal length or principal point also given. `field` names the whole
    /// (`rgbd.intrinsics`).
    pub fn from_wire(
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        k: &[f64],
        field: &str,
    ) -> Result<Self, FieldError> {
        let given = Self { fx, fy, cx, cy };
        if k.is_empty() {
            return Ok(given);
        }
        let kf = format!("{field}.k");
        if k.len() != 9 {
            return Err(FieldError::new(
                kf,
                format!(
                    "holds {} values; CameraInfo.K has 9 (3 × 3, row-major)",
                    k.len()
                ),
            ));
        }
        if k[1] != 0.0 || k[3] != 0.0 || k[6] != 0.0 || k[7] != 0.0 || k[8] != 1.0 {
            return Err(FieldError::new(
                kf,
                format!(
                    "{k:?} is not a pinhole K without skew (fx 0 cx, 0 fy cy, 0 0 1); rectify \
                     the image first"
                ),
            ));
        }
        let from_k = Self {
            fx: k[0],
            fy: k[4],
            cx: k[2],
            cy: k[5],
        };
        for (name, a, b) in [
            ("fx", fx, from_k.fx),
            ("fy", fy, from_k.fy),
            ("cx", cx, from_k.cx),
            ("cy", cy, from_k.cy),
        ] {
            if a != 0.0 && a != b {
                return Err(FieldError::new(
                    kf,
                    format!("gives {name} = {b}, but {name} = {a} is given too"),
                ));
            }
        }
        Ok(from_k)
    }
}

/// One image of a frame as the transports receive it: the declared size (0 × 0 for a PNG or
/// JPEG, whose header gives it), the encoding's wire name (empty: PNG or JPEG told by its magic
/// bytes), the row stride of a raw image (0 = packed) and the bytes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WireImage {
    pub width: u32,
    pub height: u32,
    pub encoding: String,
    /// Multi-byte raw pixels (16UC1, 32FC1) are big-endian (ROS `is_bigendian`).
    pub is_bigendian: bool,
    pub step: u32,
    pub data: Vec<u8>,
}

/// `png` or `jpeg` by the file's magic bytes, for an image sent without an encoding name.
pub fn sniff_encoding(data: &[u8]) -> Option<&'static str> {
    if data.starts_with(&[0x89, b'P', b'N', b'G']) {
        Some("png")
    } else if data.starts_with(&[0xFF, 0xD8]) {
        Some("jpeg")
    } else {
        None
    }
}

impl WireImage {
    /// The encoding name, sniffed when left empty.
    fn encoding_name(&self) -> &str {
        if self.encoding.is_empty() {
            sniff_encoding(&self.data).unwrap_or("")
        } else {
            &self.encoding
        }
    }

    /// The declared size, read from a PNG / JPEG header when both sides are 0. Errors name
    /// `{field}.width` / `{field}.data`.
    fn size(&self, compressed: bool, field: &str) -> Result<(usize, usize), FieldError> {
        let (width, height) = (self.width, self.height);
        if width > 0 && height > 0 {
            return Ok((width as usize, height as usize));
        }
        if !compressed || (width, height) != (0, 0) {
            return Err(FieldError::new(
                format!("{field}.{}", if width == 0 { "width" } else { "height" }),
                format!(
                    "the image is {width}×{height}; both sides must be > 0 (they may be left 0 only \
                     for png or jpeg, whose size is read from the file)"
                ),
            ));
        }
        let dims = ImageReader::new(Cursor::new(&self.data))
            .with_guessed_format()
            .ok()
            .and_then(|r| r.into_dimensions().ok())
            .ok_or_else(|| {
                FieldError::new(
                    format!("{field}.data"),
                    format!("not a readable PNG or JPEG ({} bytes)", self.data.len()),
                )
            })?;
        Ok((dims.0 as usize, dims.1 as usize))
    }
}

/// Reverses each `bpp`-byte pixel of the first `width` in every row (`step` bytes, 0 = packed):
/// big-endian raw pixels made little-endian. Bytes past the rows are left for the size check.
fn to_little_endian(data: &mut [u8], step: usize, bpp: usize, width: usize) {
    let row = width * bpp;
    let step = if step == 0 { row } else { step };
    if bpp < 2 || row == 0 || step < row {
        return;
    }
    for r in data.chunks_mut(step) {
        let n = r.len().min(row);
        for px in r[..n].chunks_exact_mut(bpp) {
            px.reverse();
        }
    }
}

/// A camera pose from a position and a quaternion (w, x, y, z) as sent: the quaternion is
/// normalised; a zero or non-finite one is refused naming `{field}.orientation`.
pub fn camera_pose(
    position: Point3<f64>,
    q: Quaternion<f64>,
    field: &str,
) -> Result<Isometry3<f64>, FieldError> {
    let norm = q.norm();
    if !norm.is_finite() || norm < 1e-9 {
        return Err(FieldError::new(
            format!("{field}.orientation"),
            "must be a finite, non-zero quaternion",
        ));
    }
    Ok(Isometry3::from_parts(
        position.coords.into(),
        UnitQuaternion::from_quaternion(q),
    ))
}

impl RgbdFrame {
    /// The frame from its two images as received (both transports and the CLI build it here):
    /// encodings parsed, sizes declared or read from the files, and colour and depth of one
    /// size. Pixels are checked later, by [`RgbdFrame::decode`]. `field` names the frame in
    /// errors (`rgbd.color.encoding`, `rgbd.depth`, …).
    pub fn from_wire(
        color: WireImage,
        depth: WireImage,
        intrinsics: CameraIntrinsics,
        depth_scale: Option<f64>,
        camera_to_world: Option<Isometry3<f64>>,
        field: &str,
    ) -> Result<Self, FieldError> {
        let (cf, df) = (format!("{field}.color"), format!("{field}.depth"));
        let color_encoding =
            ColorEncoding::parse(color.encoding_name(), &format!("{cf}.encoding"))?;
        let depth_encoding =
            DepthEncoding::parse(depth.encoding_name(), &format!("{df}.encoding"))?;
        let color_size = color.size(color_encoding.bytes_per_pixel().is_none(), &cf)?;
        let depth_size = depth.size(depth_encoding.bytes_per_pixel().is_none(), &df)?;
        let mut depth = depth;
        if depth.is_bigendian
            && let Some(bpp) = depth_encoding.bytes_per_pixel()
        {
            to_little_endian(&mut depth.data, depth.step as usize, bpp, depth_size.0);
        }
        if color_size != depth_size {
            return Err(FieldError::new(
                df,
                format!(
                    "the depth image is {}×{} but the colour image is {}×{}; register them to one size",
                    depth_size.0, depth_size.1, color_size.0, color_size.1
                ),
            ));
        }
        Ok(RgbdFrame {
            color: ImageData {
                encoding: color_encoding,
                data: color.data,
                step: color.step as usize,
            },
            depth: ImageData {
                encoding: depth_encoding,
                data: depth.data,
                step: depth.step as usize,
            },
            width: color_size.0,
            height: color_size.1,
            intrinsics,
            depth_scale: depth_scale.filter(|s| *s != 0.0),
            camera_to_world,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::RgbdLimits;

    const K: [f64; 9] = [525.0, 0.0, 319.5, 0.0, 526.0, 239.5, 0.0, 0.0, 1.0];

    #[test]
    fn camera_info_k_gives_the_pinhole_and_must_agree() {
        let f = "rgbd.intrinsics";
        let k = CameraIntrinsics::from_wire(0.0, 0.0, 0.0, 0.0, &K, f).unwrap();
        assert_eq!((k.fx, k.fy, k.cx, k.cy), (525.0, 526.0, 319.5, 239.5));
        assert_eq!(
            CameraIntrinsics::from_wire(525.0, 526.0, 319.5, 239.5, &K, f).unwrap(),
            k
        );
        let plain = CameraIntrinsics::from_wire(500.0, 500.0, 1.0, 2.0, &[], f).unwrap();
        assert_eq!((plain.fx, plain.cy), (500.0, 2.0));
        for (fx, k) in [
            (0.0, &K[..8]),
            (
                0.0,
                &[525.0, 0.3, 319.5, 0.0, 526.0, 239.5, 0.0, 0.0, 1.0][..],
            ),
            (
                0.0,
                &[525.0, 0.0, 319.5, 0.0, 526.0, 239.5, 0.0, 0.0, 2.0][..],
            ),
            (600.0, &K[..]),
        ] {
            let e = CameraIntrinsics::from_wire(fx, 0.0, 0.0, 0.0, k, f).unwrap_err();
            assert_eq!(e.field, "rgbd.intrinsics.k", "{e}");
        }
    }

    fn wire(encoding: &str, data: Vec<u8>, big: bool) -> WireImage {
        WireImage {
            width: 2,
            height: 1,
            encoding: encoding.into(),
            is_bigendian: big,
            step: 0,
            data,
        }
    }

    fn decoded(color: WireImage, depth: WireImage) -> crate::perception::DecodedFrame {
        let k = CameraIntrinsics::from_wire(0.0, 0.0, 0.0, 0.0, &K, "rgbd.intrinsics").unwrap();
        RgbdFrame::from_wire(color, depth, k, None, None, "rgbd")
            .unwrap()
            .decode("rgbd", &RgbdLimits::default())
            .unwrap()
    }

    /// rgba8 and bgra8 read as rgb8 with the alpha dropped; big-endian 16UC1 and 32FC1 read as
    /// their little-endian twins.
    #[test]
    fn alpha_colour_and_big_endian_depth_decode_like_their_plain_twins() {
        let mm: [u16; 2] = [800, 1234];
        let le16: Vec<u8> = mm.iter().flat_map(|v| v.to_le_bytes()).collect();
        let be16: Vec<u8> = mm.iter().flat_map(|v| v.to_be_bytes()).collect();
        let rgb = wire("rgb8", vec![10, 20, 30, 40, 50, 60], false);
        let plain = decoded(rgb.clone(), wire("16UC1", le16, false));
        for color in [
            wire("rgba8", vec![10, 20, 30, 255, 40, 50, 60, 0], false),
            wire("bgra8", vec![30, 20, 10, 7, 60, 50, 40, 7], false),
        ] {
            let other = decoded(color, wire("16UC1", be16.clone(), true));
            assert_eq!(other.rgb, plain.rgb);
            assert_eq!(other.depth, plain.depth);
        }
        assert_eq!(plain.depth, vec![0.8, 1.234]);
        let m: [f32; 2] = [0.5, 2.25];
        let be32: Vec<u8> = m.iter().flat_map(|v| v.to_be_bytes()).collect();
        let f = decoded(rgb, wire("32FC1", be32, true));
        assert_eq!(f.depth, vec![0.5, 2.25]);
    }
}
