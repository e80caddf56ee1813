//! Bottom-up saliency as in VOCUS2 (Frintrop et al. 2015; dissertation ch. 4.2.1, method.md §4):
//! the colour image in an opponent colour space, twin centre/surround Gaussian pyramids per
//! channel, centre–surround difference-of-Gaussian contrast of both polarities, fusion across
//! scales by the arithmetic mean, then across channels. Pixel-precise (the map has the image's
//! size) and without centre bias: nothing in it depends on where a pixel lies in the image.
//!
//! Steps, for an RGB image with values in [0, 1]:
//! 1. Opponent channels: intensity I = (R + G + B)/3, red–green RG = R − G, blue–yellow
//!    BY = B − (R + G)/2.
//! 2. The image is first reduced by [`SaliencyParams::base_downsample`] (box average), then for
//!    each octave o = 0 … [`SaliencyParams::octaves`] − 1: the centre layer C_o = G(σ_c) ∗ X_o and
//!    the surround layer S_o = G(√(σ_s² − σ_c²)) ∗ C_o (so that S_o is X_o blurred by σ_s, the
//!    "twin" of C_o); X_{o+1} is C_o halved.
//! 3. Contrast per octave: on–off = max(C_o − S_o, 0), off–on = max(S_o − C_o, 0).
//! 4. Fusion: each polarity's octaves are brought to the base size (bilinear) and averaged;
//!    a channel's feature map is the mean of its two polarities; the colour conspicuity is the
//!    mean of RG and BY, the saliency the mean of intensity and colour conspicuity (all
//!    arithmetic means, VOCUS2's default fusion). The result is brought to the image size and
//!    scaled to [0, 1].

/// Parameters of the saliency map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SaliencyParams {
    /// σ_c of the centre pyramid, pixels of its octave.
    pub center_sigma: f32,
    /// σ_s of the surround pyramid, pixels of its octave.
    pub surround_sigma: f32,
    /// Number of octaves.
    pub octaves: usize,
    /// The image is reduced by this factor (box average) before the pyramids.
    pub base_downsample: usize,
}

impl Default for SaliencyParams {
    /// VOCUS2's centre/surround ratio (σ_c = 3, σ_s = 13 at full resolution) scaled to a half
    /// resolution base: σ_c = 1.5, σ_s = 6.5; four octaves (down to 1/16 of the image).
    fn default() -> Self {
        Self {
            center_sigma: 1.5,
            surround_sigma: 6.5,
            octaves: 4,
            base_downsample: 2,
        }
    }
}

/// A single-channel image, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct Plane32 {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl Plane32 {
    fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            data: vec![0.0; width * height],
        }
    }
}

/// The VOCUS2 saliency map of an RGB image (`3 × width × height` bytes), with the image's
/// size, values in [0, 1] (all 0 for a uniform image: contrast below 1e-4 counts as none).
pub fn saliency_map(rgb: &[u8], width: usize, height: usize, params: &SaliencyParams) -> Plane32 {
    assert_eq!(rgb.len(), 3 * width * height, "RGB buffer size");
    let f = params.base_downsample.max(1);
    let (bw, bh) = (width.div_ceil(f), height.div_ceil(f));
    // 1. Opponent channels at the base resolution (box average over f × f pixels).
    let mut chans = [
        Plane32::new(bw, bh),
        Plane32::new(bw, bh),
        Plane32::new(bw, bh),
    ];
    for by in 0..bh {
        for bx in 0..bw {
            let (mut r, mut g, mut b, mut n) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
            for y in by * f..((by + 1) * f).min(height) {
                for x in bx * f..((bx + 1) * f).min(width) {
                    let i = 3 * (y * width + x);
                    r += rgb[i] as f32;
                    g += rgb[i + 1] as f32;
                    b += rgb[i + 2] as f32;
                    n += 1.0;
                }
            }
            let s = 1.0 / (255.0 * n);
            let (r, g, b) = (r * s, g * s, b * s);
            let k = by * bw + bx;
            chans[0].data[k] = (r + g + b) / 3.0;
            chans[1].data[k] = r - g;
            chans[2].data[k] = b - (r + g) / 2.0;
        }
    }
    // 2–4. Twin pyramids, contrast, fusion across scales and polarities per channel.
    let features: Vec<Plane32> = chans.iter().map(|c| channel_feature(c, params)).collect();
    let mut fused = Plane32::new(bw, bh);
    for k in 0..bw * bh {
        let colour = 0.5 * (features[1].data[k] + features[2].data[k]);
        fused.data[k] = 0.5 * (features[0].data[k] + colour);
    }
    let mut full = resize_bilinear(&fused, width, height);
    let max = full.data.iter().copied().fold(0.0f32, f32::max);
    // Below 1e-4 (of the [0, 1] colour range) the contrast is rounding noise of the blurs:
    // a uniform image has no salient region.
    let scale = if max > 1e-4 { 1.0 / max } else { 0.0 };
    for v in &mut full.data {
        *v *= scale;
    }
    full
}

/// The feature map of one opponent channel: the mean over octaves (at the base size) of the
/// on–off and off–on DoG contrasts, the two polarities averaged.
fn channel_feature(base: &Plane32, params: &SaliencyParams) -> Plane32 {
    let (bw, bh) = (base.width, base.height);
    let mut acc = Plane32::new(bw, bh);
    let surround_extra = (params.surround_sigma.powi(2) - params.center_sigma.powi(2))
        .max(0.0)
        .sqrt();
    let mut x = base.clone();
    let mut used = 0;
    for _ in 0..params.octaves.max(1) {
        if x.width < 2 || x.height < 2 {
            break;
        }
        let center = gaussian_blur(&x, params.center_sigma);
        let surround = gaussian_blur(&center, surround_extra);
        // |C − S| = on–off + off–on; the mean of the two polarities is half of it.
        let mut contrast = Plane32::new(x.width, x.height);
        for ((o, c), s) in contrast
            .data
            .iter_mut()
            .zip(&center.data)
            .zip(&surround.data)
        {
            let on_off = (c - s).max(0.0);
            let off_on = (s - c).max(0.0);
            *o = 0.5 * (on_off + off_on);
        }
        let up = if (x.width, x.height) == (bw, bh) {
            contrast
        } else {
            resize_bilinear(&contrast, bw, bh)
        };
        for (a, u) in acc.data.iter_mut().zip(&up.data) {
            *a += u;
        }
        used += 1;
        x = halve(&center);
    }
    let inv = 1.0 / used.max(1) as f32;
    for a in &mut acc.data {
        *a *= inv;
    }
    acc
}

/// Separable Gaussian blur (kernel radius ⌈3σ⌉, borders clamped).
pub fn gaussian_blur(img: &Plane32, sigma: f32) -> Plane32 {
    if sigma <= 0.0 {
        return img.clone();
    }
    let r = (3.0 * sigma).ceil() as isize;
    let mut k: Vec<f32> = (-r..=r)
        .map(|i| (-(i * i) as f32 / (2.0 * sigma * sigma)).exp())
        .collect();
    let s: f32 = k.iter().sum();
    for v in &mut k {
        *v /= s;
    }
    let (w, h) = (img.width as isize, img.height as isize);
    let mut tmp = Plane32::new(img.width, img.height);
    for y in 0..h {
        let row = &img.data[(y * w) as usize..((y + 1) * w) as usize];
        let out = &mut tmp.data[(y * w) as usize..((y + 1) * w) as usize];
        for x in 0..w {
            let mut acc = 0.0;
            if x >= r && x + r < w {
                for (j, kv) in k.iter().enumerate() {
                    acc += kv * row[(x - r + j as isize) as usize];
                }
            } else {
                for (j, kv) in k.iter().enumerate() {
                    acc += kv * row[(x - r + j as isize).clamp(0, w - 1) as usize];
                }
            }
            out[x as usize] = acc;
        }
    }
    let mut out = Plane32::new(img.width, img.height);
    for y in 0..h {
        let o = &mut out.data[(y * w) as usize..((y + 1) * w) as usize];
        for (j, kv) in k.iter().enumerate() {
            let yy = (y - r + j as isize).clamp(0, h - 1);
            let src = &tmp.data[(yy * w) as usize..((yy + 1) * w) as usize];
            for (ov, sv) in o.iter_mut().zip(src) {
                *ov += kv * sv;
            }
        }
    }
    out
}

/// Halves an image by 2 × 2 box averaging (odd edges keep their last row/column).
fn halve(img: &Plane32) -> Plane32 {
    let (w, h) = (img.width.div_ceil(2), img.height.div_ceil(2));
    let mut out = Plane32::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let (x0, y0) = (2 * x, 2 * y);
            let (x1, y1) = ((x0 + 1).min(img.width - 1), (y0 + 1).min(img.height - 1));
            let at = |xx: usize, yy: usize| img.data[yy * img.width + xx];
            out.data[y * w + x] = 0.25 * (at(x0, y0) + at(x1, y0) + at(x0, y1) + at(x1, y1));
        }
    }
    out
}

/// Bilinear resize (pixel centres aligned).
fn resize_bilinear(img: &Plane32, width: usize, height: usize) -> Plane32 {
    let mut out = Plane32::new(width, height);
    let sx = img.width as f32 / width as f32;
    let sy = img.height as f32 / height as f32;
    let xs: Vec<(usize, usize, f32)> = (0..width)
        .map(|x| {
            let fx = ((x as f32 + 0.5) * sx - 0.5).clamp(0.0, (img.width - 1) as f32);
            let x0 = fx.floor() as usize;
            (x0, (x0 + 1).min(img.width - 1), fx - x0 as f32)
        })
        .collect();
    for y in 0..height {
        let fy = ((y as f32 + 0.5) * sy - 0.5).clamp(0.0, (img.height - 1) as f32);
        let y0 = fy.floor() as usize;
        let y1 = (y0 + 1).min(img.height - 1);
        let ty = fy - y0 as f32;
        let (r0, r1) = (
            &img.data[y0 * img.width..(y0 + 1) * img.width],
            &img.data[y1 * img.width..(y1 + 1) * img.width],
        );
        for (x, &(x0, x1, tx)) in xs.iter().enumerate() {
            let a = r0[x0] + tx * (r0[x1] - r0[x0]);
            let b = r1[x0] + tx * (r1[x1] - r1[x0]);
            out.data[y * width + x] = a + ty * (b - a);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grey 160×120 image with a red 16×16 square at (x, y).
    fn image_with_square(x: usize, y: usize) -> Vec<u8> {
        let (w, h) = (160, 120);
        let mut rgb = vec![120u8; 3 * w * h];
        for v in y..y + 16 {
            for u in x..x + 16 {
                let i = 3 * (v * w + u);
                rgb[i..i + 3].copy_from_slice(&[220, 30, 30]);
            }
        }
        rgb
    }

    fn mean_in(map: &Plane32, x: usize, y: usize, s: usize) -> f32 {
        let mut acc = 0.0;
        for v in y..y + s {
            for u in x..x + s {
                acc += map.data[v * map.width + u];
            }
        }
        acc / (s * s) as f32
    }

    #[test]
    fn a_coloured_square_stands_out_wherever_it_is() {
        let p = SaliencyParams::default();
        for (x, y) in [(72, 52), (4, 4), (136, 96)] {
            let m = saliency_map(&image_with_square(x, y), 160, 120, &p);
            assert_eq!((m.width, m.height), (160, 120));
            let inside = mean_in(&m, x, y, 16);
            let mean = m.data.iter().sum::<f32>() / m.data.len() as f32;
            assert!(
                inside > 4.0 * mean,
                "({x},{y}): inside {inside}, mean {mean}"
            );
            // Far from the square the map is (nearly) zero.
            let (fx, fy) = if x > 80 { (10, 10) } else { (130, 90) };
            assert!(mean_in(&m, fx, fy, 10) < 0.05 * inside);
            assert!(m.data.iter().all(|v| (0.0..=1.0).contains(v)));
        }
    }

    #[test]
    fn no_centre_bias_and_uniform_images_give_zero() {
        let p = SaliencyParams::default();
        // The same square at mirrored places gets the same saliency.
        let a = saliency_map(&image_with_square(20, 30), 160, 120, &p);
        let b = saliency_map(&image_with_square(124, 74), 160, 120, &p);
        let (sa, sb) = (mean_in(&a, 20, 30, 16), mean_in(&b, 124, 74, 16));
        assert!((sa - sb).abs() < 0.1 * sa, "{sa} vs {sb}");
        let flat = saliency_map(&vec![90u8; 3 * 64 * 48], 64, 48, &p);
        assert!(flat.data.iter().all(|v| *v == 0.0));
    }

    #[test]
    fn blur_keeps_the_mean_and_resize_is_exact_on_constants() {
        // An impulse away from the borders keeps its mass and spreads symmetrically.
        let mut img = Plane32::new(30, 30);
        img.data[15 * 30 + 15] = 1.0;
        let b = gaussian_blur(&img, 1.5);
        assert!((b.data.iter().sum::<f32>() - 1.0).abs() < 1e-4);
        let c = b.data[15 * 30 + 15];
        assert!(c < 0.2 && c > b.data[15 * 30 + 16]);
        assert!((b.data[15 * 30 + 16] - b.data[16 * 30 + 15]).abs() < 1e-7);
        let c = Plane32 {
            width: 5,
            height: 4,
            data: vec![0.25; 20],
        };
        let r = resize_bilinear(&c, 17, 9);
        assert!(r.data.iter().all(|v| (v - 0.25).abs() < 1e-6));
    }
}
