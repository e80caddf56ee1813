//! `gen-grasp-type-data`: renders random RGB-D tabletop scenes (640 × 480, [`scene`]) with
//! per-pixel grasp-type labels ([`labels`], models/grasp_type/LABELS.md) and writes them as the
//! grasp-type network sees them: resized to the model's input size by graspd's own
//! preprocessing (`graspd_core::perception::resized_planes`), so training and serving read
//! identical tensors.
//!
//! ```text
//! gen-grasp-type-data --out DIR --count N --seed S [--width 160 --height 120] [--previews K]
//! ```
//! Writes `DIR/x.npy` (float32 [N, 4, H, W]: R, G, B in 0…255, depth in m, 0 = no reading),
//! `DIR/y.npy` (uint8 [N, H, W]: bit s−1 set where type s suits the pixel), `DIR/meta.json`,
//! and for the first K samples the full frames in the own-data format of train.py
//! (`NNNNN_rgb.png`, `NNNNN_depth.png` 16-bit mm, `NNNNN_labels.png` 8-bit label bytes).
//! Sample i is drawn from seed `S · 1 000 003 + i`, so the output does not depend on `--threads`.

use clap::Parser;
use graspd_model_data::{Frame, Sample, labels, npy_header, sample};
use image::{ExtendedColorType, ImageEncoder, codecs::png::PngEncoder};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::mpsc;

#[derive(Parser, Debug)]
#[command(about = "Generate grasp-type training data (models/grasp_type)")]
struct Args {
    /// Output folder (created).
    #[arg(long)]
    out: PathBuf,
    /// Number of scenes.
    #[arg(long)]
    count: usize,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Model input width.
    #[arg(long, default_value_t = 160)]
    width: usize,
    /// Model input height.
    #[arg(long, default_value_t = 120)]
    height: usize,
    /// Also write the first K scenes as full-size PNGs (own-data format).
    #[arg(long, default_value_t = 0)]
    previews: usize,
    /// Worker threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
}

fn create(path: &Path) -> Result<BufWriter<File>, String> {
    File::create(path)
        .map(BufWriter::new)
        .map_err(|e| format!("{}: {e}", path.display()))
}

fn write_png(
    path: &Path,
    data: &[u8],
    w: usize,
    h: usize,
    ty: ExtendedColorType,
) -> Result<(), String> {
    let f = create(path)?;
    PngEncoder::new(f)
        .write_image(data, w as u32, h as u32, ty)
        .map_err(|e| format!("{}: {e}", path.display()))
}

fn write_preview(dir: &Path, i: usize, f: &Frame) -> Result<(), String> {
    let (w, h) = (f.width, f.height);
    write_png(
        &dir.join(format!("{i:05}_rgb.png")),
        &f.rgb,
        w,
        h,
        ExtendedColorType::Rgb8,
    )?;
    // The encoder takes native-endian 16-bit samples (PNG stores them big-endian).
    let depth: Vec<u8> = f
        .depth
        .iter()
        .flat_map(|d| ((d * 1000.0).round().clamp(0.0, 65535.0) as u16).to_ne_bytes())
        .collect();
    write_png(
        &dir.join(format!("{i:05}_depth.png")),
        &depth,
        w,
        h,
        ExtendedColorType::L16,
    )?;
    write_png(
        &dir.join(format!("{i:05}_labels.png")),
        &f.labels,
        w,
        h,
        ExtendedColorType::L8,
    )
}

fn run(args: Args) -> Result<(), String> {
    std::fs::create_dir_all(&args.out).map_err(|e| format!("{}: {e}", args.out.display()))?;
    let (n, w, h) = (args.count, args.width, args.height);
    let mut xf = create(&args.out.join("x.npy"))?;
    let mut yf = create(&args.out.join("y.npy"))?;
    let io = |e: std::io::Error| e.to_string();
    xf.write_all(&npy_header("<f4", &[n, 4, h, w]))
        .map_err(io)?;
    yf.write_all(&npy_header("|u1", &[n, h, w])).map_err(io)?;
    let threads = match args.threads {
        0 => std::thread::available_parallelism().map_or(1, |t| t.get()),
        t => t,
    };
    let mut type_pixels = [0u64; 6];
    let mut object_pixels = 0u64;
    let started = std::time::Instant::now();
    std::thread::scope(|s| -> Result<(), String> {
        let (tx, rx) = mpsc::sync_channel::<(usize, Result<Sample, String>)>(4 * threads);
        for t in 0..threads {
            let tx = tx.clone();
            let args = &args;
            s.spawn(move || {
                for i in (t..n).step_by(threads) {
                    if tx
                        .send((
                            i,
                            sample(args.seed, i, args.width, args.height, i < args.previews),
                        ))
                        .is_err()
                    {
                        return;
                    }
                }
            });
        }
        drop(tx);
        // Samples arrive out of order; write them in order.
        let mut pending = BTreeMap::new();
        let mut next = 0;
        for (i, sample) in rx {
            pending.insert(i, sample?);
            while let Some(sample) = pending.remove(&next) {
                for v in &sample.x {
                    xf.write_all(&v.to_le_bytes()).map_err(io)?;
                }
                yf.write_all(&sample.y).map_err(io)?;
                for &l in &sample.y {
                    object_pixels += u64::from(l != 0);
                    for (b, c) in type_pixels.iter_mut().enumerate() {
                        *c += u64::from(l >> b & 1);
                    }
                }
                if let Some(f) = &sample.full {
                    write_preview(&args.out, next, f)?;
                }
                next += 1;
                if next % 100 == 0 || next == n {
                    eprintln!(
                        "{next}/{n} scenes, {:.0} s",
                        started.elapsed().as_secs_f64()
                    );
                }
            }
        }
        Ok(())
    })?;
    xf.flush().map_err(io)?;
    yf.flush().map_err(io)?;
    let total = (n * w * h) as f64;
    let meta = serde_json::json!({
        "generator": "gen-grasp-type-data",
        "seed": args.seed,
        "count": n,
        "input": {"width": w, "height": h, "channels": ["R", "G", "B", "depth_m"]},
        "source_size": [640, 480],
        "types": labels::NAMES,
        "object_pixel_share": object_pixels as f64 / total,
        "type_pixel_share": labels::NAMES.iter().zip(type_pixels)
            .map(|(name, c)| (name.to_string(), serde_json::json!(c as f64 / total)))
            .collect::<serde_json::Map<_, _>>(),
        "seconds": started.elapsed().as_secs_f64(),
    });
    std::fs::write(
        args.out.join("meta.json"),
        serde_json::to_string_pretty(&meta).map_err(|e| e.to_string())?,
    )
    .map_err(io)?;
    Ok(())
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("gen-grasp-type-data: {e}");
            ExitCode::FAILURE
        }
    }
}
