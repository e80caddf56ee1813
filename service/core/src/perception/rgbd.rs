//! The RGB-D frame as robot stacks send it (method.md §4; ROS `sensor_msgs/Image` and
//! `CameraInfo` conventions) and its decoding into a registered colour + metric depth image.
//!
//! Colour comes as raw `rgb8` / `bgr8` / `rgba8` / `bgra8` rows or as PNG / JPEG bytes; depth as raw `16UC1`
//! (millimetres), raw `32FC1` (metres) or a 16-bit grayscale PNG (millimetres, the format of
//! most RGB-D data sets). Raw rows are little-endian with a row stride `step` (0: packed). Depth
//! must be registered to the colour image: both have the frame's `width` × `height`, and pixel
//! (u, v) of one is pixel (u, v) of the other.
//!
//! The frame as the transports receive it (sizes, encoding names, `is_bigendian`, `CameraInfo.K`)
//! is read in [`super::rgbd_wire`].
//!
//! Every check names the offending field (`rgbd.color.data`, `rgbd.depth.encoding`,
//! `rgbd.intrinsics.fx`, …) so that the transports can answer INVALID_ARGUMENT / HTTP 400.

use crate::error::FieldError;
use image::{DynamicImage, ImageFormat, ImageReader, Limits};
use nalgebra::Isometry3;
use std::fmt;
use std::io::Cursor;

/// Encodings of the colour image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColorEncoding {
    /// Raw 8-bit R, G, B per pixel (ROS `rgb8`).
    Rgb8,
    /// Raw 8-bit B, G, R per pixel (ROS `bgr8`, OpenCV's order).
    Bgr8,
    /// Raw 8-bit R, G, B, A per pixel (ROS `rgba8`; alpha is dropped).
    Rgba8,
    /// Raw 8-bit B, G, R, A per pixel (ROS `bgra8`; alpha is dropped).
    Bgra8,
    /// A PNG file (8- or 16-bit, grey, RGB or RGBA; alpha is dropped).
    Png,
    /// A JPEG file.
    Jpeg,
}

impl ColorEncoding {
    /// Parses the wire name (`rgb8`, `bgr8`, `rgba8`, `bgra8`, `png`, `jpeg`/`jpg`,
    /// case-insensitive).
    pub fn parse(name: &str, field: &str) -> Result<Self, FieldError> {
        match name.to_ascii_lowercase().as_str() {
            "rgb8" => Ok(Self::Rgb8),
            "bgr8" => Ok(Self::Bgr8),
            "rgba8" => Ok(Self::Rgba8),
            "bgra8" => Ok(Self::Bgra8),
            "png" => Ok(Self::Png),
            "jpeg" | "jpg" => Ok(Self::Jpeg),
            _ => Err(FieldError::new(
                field,
                format!(
                    "unknown colour encoding {name:?}; use rgb8, bgr8, rgba8, bgra8, png or jpeg"
                ),
            )),
        }
    }

    /// Bytes per pixel of a raw encoding (`None` for compressed ones).
    pub fn bytes_per_pixel(self) -> Option<usize> {
        match self {
            Self::Rgb8 | Self::Bgr8 => Some(3),
            Self::Rgba8 | Self::Bgra8 => Some(4),
            Self::Png | Self::Jpeg => None,
        }
    }
}

impl fmt::Display for ColorEncoding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Rgb8 => "rgb8",
            Self::Bgr8 => "bgr8",
            Self::Rgba8 => "rgba8",
            Self::Bgra8 => "bgra8",
            Self::Png => "png",
            Self::Jpeg => "jpeg",
        })
    }
}

/// Encodings of the depth image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepthEncoding {
    /// Raw little-endian u16 per pixel, in depth units (ROS `16UC1`: millimetres; 0 = no reading).
    Mono16,
    /// Raw little-endian f32 per pixel, metres (ROS `32FC1`; 0, NaN and ±inf = no reading).
    Float32,
    /// A 16-bit grayscale PNG in depth units (millimetres by default; 0 = no reading).
    Png16,
}

impl DepthEncoding {
    /// Parses the wire name (`16UC1`/`mono16`, `32FC1`, `png`).
    pub fn parse(name: &str, field: &str) -> Result<Self, FieldError> {
        match name.to_ascii_lowercase().as_str() {
            "16uc1" | "mono16" => Ok(Self::Mono16),
            "32fc1" => Ok(Self::Float32),
            "png" | "png16" => Ok(Self::Png16),
            _ => Err(FieldError::new(
                field,
                format!("unknown depth encoding {name:?}; use 16UC1, 32FC1 or png"),
            )),
        }
    }

    /// Bytes per pixel of a raw encoding (`None` for PNG).
    pub fn bytes_per_pixel(self) -> Option<usize> {
        match self {
            Self::Mono16 => Some(2),
            Self::Float32 => Some(4),
            Self::Png16 => None,
        }
    }

    /// Metres per depth unit when the caller gives no scale: 1 mm for the 16-bit encodings,
    /// 1 m for `32FC1`.
    pub fn default_scale(self) -> f64 {
        match self {
            Self::Mono16 | Self::Png16 => 0.001,
            Self::Float32 => 1.0,
        }
    }
}

impl fmt::Display for DepthEncoding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Mono16 => "16UC1",
            Self::Float32 => "32FC1",
            Self::Png16 => "png",
        })
    }
}

/// One image of the frame as received: its encoding, bytes and (raw encodings) row stride.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageData<E> {
    pub encoding: E,
    pub data: Vec<u8>,
    /// Bytes per row of a raw image; 0 means packed (`width × bytes per pixel`). Ignored for
    /// PNG / JPEG.
    pub step: usize,
}

/// Pinhole intrinsics in pixels, as `CameraInfo.K`: a camera-frame point (x, y, z) (x right,
/// y down, z forward) appears at pixel u = fx·x/z + cx, v = fy·y/z + cy, pixel centres at
/// integer coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraIntrinsics {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

impl CameraIntrinsics {
    /// Checks that fx, fy are finite and positive and cx, cy finite (`field` names the whole,
    /// e.g. `rgbd.intrinsics`).
    pub fn validate(&self, field: &str) -> Result<(), FieldError> {
        for (name, v) in [("fx", self.fx), ("fy", self.fy)] {
            if !v.is_finite() || v <= 0.0 {
                return Err(FieldError::new(
                    format!("{field}.{name}"),
                    format!("{v} is not a focal length; it must be finite and > 0 pixels"),
                ));
            }
        }
        for (name, v) in [("cx", self.cx), ("cy", self.cy)] {
            if !v.is_finite() {
                return Err(FieldError::new(
                    format!("{field}.{name}"),
                    format!("{v} is not a principal point coordinate; it must be finite"),
                ));
            }
        }
        Ok(())
    }
}

/// An RGB-D frame as received (method.md §4): registered colour and depth of `width` ×
/// `height` pixels, the pinhole intrinsics, the depth scale and, optionally, where the camera
/// is in the world.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbdFrame {
    pub color: ImageData<ColorEncoding>,
    pub depth: ImageData<DepthEncoding>,
    pub width: usize,
    pub height: usize,
    pub intrinsics: CameraIntrinsics,
    /// Metres per depth unit; `None`: [`DepthEncoding::default_scale`].
    pub depth_scale: Option<f64>,
    /// Camera-to-world transform (camera frame as in [`CameraIntrinsics`]). With it, clouds
    /// and results are in the world frame; without it, in the camera frame.
    pub camera_to_world: Option<Isometry3<f64>>,
}

/// Limits on untrusted frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RgbdLimits {
    /// Largest `width × height` accepted (also bounds what a PNG / JPEG may decode to).
    pub max_pixels: usize,
}

impl Default for RgbdLimits {
    /// 4096 × 4096 pixels (16.8 M).
    fn default() -> Self {
        Self {
            max_pixels: 4096 * 4096,
        }
    }
}

/// A decoded frame: packed RGB and metric depth, one entry per pixel in row-major order.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedFrame {
    pub width: usize,
    pub height: usize,
    /// R, G, B per pixel (`3 × width × height` bytes).
    pub rgb: Vec<u8>,
    /// Depth along the optical axis in metres; 0.0 where there is no valid reading (the sensor
    /// gave 0, NaN, ±inf or a negative value). Never NaN.
    pub depth: Vec<f32>,
    pub intrinsics: CameraIntrinsics,
    pub camera_to_world: Option<Isometry3<f64>>,
    /// Number of pixels with a valid depth.
    pub valid_depth: usize,
}

impl DecodedFrame {
    /// Depth at pixel (u, v) in metres, `None` if invalid or outside the image.
    pub fn depth_at(&self, u: usize, v: usize) -> Option<f32> {
        (u < self.width && v < self.height)
            .then(|| self.depth[v * self.width + u])
            .filter(|d| *d > 0.0)
    }

    /// R, G, B at pixel (u, v).
    pub fn rgb_at(&self, u: usize, v: usize) -> [u8; 3] {
        let i = 3 * (v * self.width + u);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }
}

impl RgbdFrame {
    /// Validates and decodes the frame. `field` names the frame in errors (e.g. `rgbd`).
    pub fn decode(&self, field: &str, limits: &RgbdLimits) -> Result<DecodedFrame, FieldError> {
        let (w, h) = (self.width, self.height);
        if w == 0 || h == 0 {
            return Err(FieldError::new(
                format!("{field}.{}", if w == 0 { "width" } else { "height" }),
                format!("the image is {w}×{h}; both sides must be > 0"),
            ));
        }
        let pixels = w.saturating_mul(h);
        if pixels > limits.max_pixels {
            return Err(FieldError::new(
                field,
                format!(
                    "{w}×{h} = {pixels} pixels exceed the configured limit of {}",
                    limits.max_pixels
                ),
            ));
        }
        self.intrinsics.validate(&format!("{field}.intrinsics"))?;
        let scale = match self.depth_scale {
            Some(s) if !s.is_finite() || s <= 0.0 => {
                return Err(FieldError::new(
                    format!("{field}.depth_scale"),
                    format!("{s} must be finite and > 0 (metres per depth unit)"),
                ));
            }
            Some(s) => s,
            None => self.depth.encoding.default_scale(),
        };
        if let Some(t) = &self.camera_to_world {
            let ok = t.translation.vector.iter().all(|v| v.is_finite())
                && t.rotation.coords.iter().all(|v| v.is_finite());
            if !ok {
                return Err(FieldError::new(
                    format!("{field}.camera_to_world"),
                    "the transform has NaN or infinite entries",
                ));
            }
        }
        let rgb = decode_color(&self.color, w, h, &format!("{field}.color"), limits)?;
        let depth = decode_depth(&self.depth, w, h, scale, &format!("{field}.depth"), limits)?;
        let valid_depth = depth.iter().filter(|d| **d > 0.0).count();
        if valid_depth == 0 {
            return Err(FieldError::new(
                format!("{field}.depth.data"),
                "no valid depth pixel (all are 0, NaN, infinite or negative)",
            ));
        }
        Ok(DecodedFrame {
            width: w,
            height: h,
            rgb,
            depth,
            intrinsics: self.intrinsics,
            camera_to_world: self.camera_to_world,
            valid_depth,
        })
    }
}

/// Checks the byte count of a raw image and returns its row stride.
fn raw_rows(
    data: &[u8],
    step: usize,
    bpp: usize,
    w: usize,
    h: usize,
    encoding: &dyn fmt::Display,
    field: &str,
) -> Result<usize, FieldError> {
    let row = w * bpp;
    let step = if step == 0 { row } else { step };
    if step < row {
        return Err(FieldError::new(
            format!("{field}.step"),
            format!("{step} bytes per row, but {w} pixels of {encoding} need {row}"),
        ));
    }
    let expected = step * h;
    if data.len() != expected {
        return Err(FieldError::new(
            format!("{field}.data"),
            format!(
                "{} bytes, expected {expected} for {w}×{h} {encoding}{}",
                data.len(),
                if step == row {
                    String::new()
                } else {
                    format!(" with step {step}")
                }
            ),
        ));
    }
    Ok(step)
}

/// Decodes a PNG / JPEG with the frame's pixel limit and checks it has the frame's size.
fn decode_file(
    data: &[u8],
    format: ImageFormat,
    w: usize,
    h: usize,
    field: &str,
    limits: &RgbdLimits,
) -> Result<DynamicImage, FieldError> {
    let name = match format {
        ImageFormat::Png => "PNG",
        _ => "JPEG",
    };
    let mut reader = ImageReader::with_format(Cursor::new(data), format);
    let mut lim = Limits::default();
    // Sides as large as the frame's pixel budget allows, memory for 16-bit RGBA of that many.
    let side = u32::try_from(limits.max_pixels).unwrap_or(u32::MAX);
    lim.max_image_width = Some(side);
    lim.max_image_height = Some(side);
    lim.max_alloc = Some((limits.max_pixels as u64).saturating_mul(8).max(1 << 20));
    reader.limits(lim);
    let img = reader.decode().map_err(|e| {
        FieldError::new(
            format!("{field}.data"),
            format!("not a readable {name} ({} bytes): {e}", data.len()),
        )
    })?;
    if (img.width() as usize, img.height() as usize) != (w, h) {
        return Err(FieldError::new(
            format!("{field}.data"),
            format!(
                "the {name} is {}×{}, but the frame is {w}×{h} (colour and depth must be \
                 registered, of the frame's size)",
                img.width(),
                img.height()
            ),
        ));
    }
    Ok(img)
}

fn decode_color(
    img: &ImageData<ColorEncoding>,
    w: usize,
    h: usize,
    field: &str,
    limits: &RgbdLimits,
) -> Result<Vec<u8>, FieldError> {
    match img.encoding {
        ColorEncoding::Rgb8 | ColorEncoding::Bgr8 | ColorEncoding::Rgba8 | ColorEncoding::Bgra8 => {
            let bpp = img.encoding.bytes_per_pixel().unwrap_or(3);
            let bgr = matches!(img.encoding, ColorEncoding::Bgr8 | ColorEncoding::Bgra8);
            let step = raw_rows(&img.data, img.step, bpp, w, h, &img.encoding, field)?;
            let mut rgb = Vec::with_capacity(3 * w * h);
            for row in img.data.chunks_exact(step) {
                let row = &row[..bpp * w];
                if img.encoding == ColorEncoding::Rgb8 {
                    rgb.extend_from_slice(row);
                } else {
                    for px in row.chunks_exact(bpp) {
                        if bgr {
                            rgb.extend_from_slice(&[px[2], px[1], px[0]]);
                        } else {
                            rgb.extend_from_slice(&px[..3]);
                        }
                    }
                }
            }
            Ok(rgb)
        }
        ColorEncoding::Png => Ok(
            decode_file(&img.data, ImageFormat::Png, w, h, field, limits)?
                .into_rgb8()
                .into_raw(),
        ),
        ColorEncoding::Jpeg => Ok(
            decode_file(&img.data, ImageFormat::Jpeg, w, h, field, limits)?
                .into_rgb8()
                .into_raw(),
        ),
    }
}

/// Metres from a raw depth value; 0.0 for every invalid reading.
fn metres(raw: f64, scale: f64) -> f32 {
    let d = raw * scale;
    if d.is_finite() && d > 0.0 {
        d as f32
    } else {
        0.0
    }
}

fn decode_depth(
    img: &ImageData<DepthEncoding>,
    w: usize,
    h: usize,
    scale: f64,
    field: &str,
    limits: &RgbdLimits,
) -> Result<Vec<f32>, FieldError> {
    let mut depth = Vec::with_capacity(w * h);
    match img.encoding {
        DepthEncoding::Mono16 => {
            let step = raw_rows(&img.data, img.step, 2, w, h, &img.encoding, field)?;
            for row in img.data.chunks_exact(step) {
                depth.extend(
                    row[..2 * w]
                        .chunks_exact(2)
                        .map(|b| metres(u16::from_le_bytes([b[0], b[1]]) as f64, scale)),
                );
            }
        }
        DepthEncoding::Float32 => {
            let step = raw_rows(&img.data, img.step, 4, w, h, &img.encoding, field)?;
            for row in img.data.chunks_exact(step) {
                depth.extend(
                    row[..4 * w].chunks_exact(4).map(|b| {
                        metres(f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64, scale)
                    }),
                );
            }
        }
        DepthEncoding::Png16 => {
            let decoded = decode_file(&img.data, ImageFormat::Png, w, h, field, limits)?;
            let DynamicImage::ImageLuma16(gray) = decoded else {
                return Err(FieldError::new(
                    format!("{field}.data"),
                    format!(
                        "a depth PNG must be 16-bit grayscale, this one is {:?}",
                        decoded.color()
                    ),
                ));
            };
            depth.extend(gray.as_raw().iter().map(|&v| metres(v as f64, scale)));
        }
    }
    Ok(depth)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(w: usize, h: usize) -> RgbdFrame {
        let mut depth = Vec::new();
        for i in 0..w * h {
            depth.extend_from_slice(&(500 + i as u16).to_le_bytes());
        }
        RgbdFrame {
            color: ImageData {
                encoding: ColorEncoding::Bgr8,
                data: (0..3 * w * h).map(|i| (i % 251) as u8).collect(),
                step: 0,
            },
            depth: ImageData {
                encoding: DepthEncoding::Mono16,
                data: depth,
                step: 0,
            },
            width: w,
            height: h,
            intrinsics: CameraIntrinsics {
                fx: 500.0,
                fy: 500.0,
                cx: w as f64 / 2.0,
                cy: h as f64 / 2.0,
            },
            depth_scale: None,
            camera_to_world: None,
        }
    }

    #[test]
    fn raw_bgr8_and_16uc1_decode() {
        let f = frame(4, 3).decode("rgbd", &RgbdLimits::default()).unwrap();
        assert_eq!(f.rgb_at(0, 0), [2, 1, 0]);
        assert_eq!(f.rgb_at(1, 0), [5, 4, 3]);
        assert_eq!(f.depth_at(1, 1), Some(0.505));
        assert_eq!(f.valid_depth, 12);
    }

    #[test]
    fn padded_rows_are_read_by_step() {
        let mut fr = frame(2, 2);
        // Depth rows of 2 pixels padded to 6 bytes.
        fr.depth.data = vec![0xe8, 0x03, 0, 0, 0xaa, 0xbb, 0xd0, 0x07, 0, 0, 0xcc, 0xdd];
        fr.depth.step = 6;
        let f = fr.decode("rgbd", &RgbdLimits::default()).unwrap();
        assert_eq!(f.depth, vec![1.0, 0.0, 2.0, 0.0]);
        assert_eq!(f.valid_depth, 2);
        fr.depth.step = 3;
        let e = fr.decode("rgbd", &RgbdLimits::default()).unwrap_err();
        assert_eq!(e.field, "rgbd.depth.step");
    }

    #[test]
    fn float_depth_invalid_values_become_zero() {
        let mut fr = frame(4, 1);
        fr.depth.encoding = DepthEncoding::Float32;
        fr.depth.data = [0.8f32, f32::NAN, f32::INFINITY, -1.0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let f = fr.decode("rgbd", &RgbdLimits::default()).unwrap();
        assert_eq!(f.depth, vec![0.8, 0.0, 0.0, 0.0]);
        assert!(f.depth.iter().all(|d| !d.is_nan()));
    }

    #[test]
    fn encodings_parse_and_reject() {
        assert_eq!(
            ColorEncoding::parse("BGR8", "rgbd.color.encoding").unwrap(),
            ColorEncoding::Bgr8
        );
        assert_eq!(
            DepthEncoding::parse("16UC1", "x").unwrap(),
            DepthEncoding::Mono16
        );
        let e = ColorEncoding::parse("yuv422", "rgbd.color.encoding").unwrap_err();
        assert_eq!(e.field, "rgbd.color.encoding");
        assert!(e.message.contains("yuv422"));
        let e = DepthEncoding::parse("8UC1", "rgbd.depth.encoding").unwrap_err();
        assert_eq!(e.field, "rgbd.depth.encoding");
    }
}
