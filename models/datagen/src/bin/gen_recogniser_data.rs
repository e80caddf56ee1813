//! `gen-recogniser-data`: renders cluttered tabletop scenes, segments and crops them as graspd
//! does and writes each object's crop with its class (graspd_model_data::recognition,
//! models/recogniser/MODEL_CARD.md).
//!
//! ```text
//! gen-recogniser-data --out DIR --scenes N --seed S [--unseen] [--threads T]
//! ```
//! Writes `DIR/crop.npy` (float32 [M, 5, 64, 64]), `DIR/size.npy` (float32 [M, 3]),
//! `DIR/label.npy` (uint8 [M], indices into the classes), `DIR/source.npy` (uint8 [M]: the
//! known object's index, 12 for the unseen chips can, 255 for a procedural object) and
//! `DIR/meta.json` (classes, counts per class, segments left out). Scene i is drawn from seed `S · 1 000 003 + i`, so the output
//! does not depend on `--threads`.

use clap::Parser;
use graspd_core::perception::recognition::{CROP_CHANNELS, CROP_SIDE, SIZE_FEATURES};
use graspd_model_data::npy_header;
use graspd_model_data::recognition::{SceneCrops, class_names, recognition_sample};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::mpsc;

#[derive(Parser, Debug)]
#[command(about = "Generate recogniser training data (models/recogniser)")]
struct Args {
    /// Output folder (created).
    #[arg(long)]
    out: PathBuf,
    /// Number of scenes.
    #[arg(long)]
    scenes: usize,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Add the chips can, never in training, as a 13th YCB object labelled unknown.
    #[arg(long)]
    unseen: bool,
    /// Worker threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
}

fn run(args: Args) -> Result<(), String> {
    let out = &args.out;
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let threads = match args.threads {
        0 => std::thread::available_parallelism().map_or(1, |t| t.get()),
        t => t,
    };
    let n = args.scenes;
    let started = std::time::Instant::now();
    let mut scenes: Vec<SceneCrops> = Vec::with_capacity(n);
    std::thread::scope(|s| -> Result<(), String> {
        let (tx, rx) = mpsc::sync_channel::<(usize, Result<SceneCrops, String>)>(4 * threads);
        for t in 0..threads {
            let tx = tx.clone();
            let args = &args;
            s.spawn(move || {
                for i in (t..n).step_by(threads) {
                    if tx
                        .send((i, recognition_sample(args.seed, i, args.unseen)))
                        .is_err()
                    {
                        return;
                    }
                }
            });
        }
        drop(tx);
        // Scenes arrive out of order; keep them in order.
        let mut pending = BTreeMap::new();
        for (i, r) in rx {
            pending.insert(i, r?);
            while let Some(sc) = pending.remove(&scenes.len()) {
                scenes.push(sc);
                let done = scenes.len();
                if done.is_multiple_of(100) || done == n {
                    eprintln!(
                        "{done}/{n} scenes, {:.0} s",
                        started.elapsed().as_secs_f64()
                    );
                }
            }
        }
        Ok(())
    })?;
    let objects: Vec<_> = scenes.iter().flat_map(|s| s.labelled()).collect();
    let m = objects.len();
    let io = |e: std::io::Error| e.to_string();
    let create = |name: &str| {
        let p = out.join(name);
        File::create(&p)
            .map(BufWriter::new)
            .map_err(|e| format!("{}: {e}", p.display()))
    };
    let mut crop = create("crop.npy")?;
    crop.write_all(&npy_header(
        "<f4",
        &[m, CROP_CHANNELS, CROP_SIDE, CROP_SIDE],
    ))
    .map_err(io)?;
    let mut size = create("size.npy")?;
    size.write_all(&npy_header("<f4", &[m, SIZE_FEATURES]))
        .map_err(io)?;
    let mut label = create("label.npy")?;
    label.write_all(&npy_header("|u1", &[m])).map_err(io)?;
    let mut source = create("source.npy")?;
    source.write_all(&npy_header("|u1", &[m])).map_err(io)?;
    let classes = class_names();
    let mut per_class = vec![0usize; classes.len()];
    for o in &objects {
        for v in &o.crop.planes {
            crop.write_all(&v.to_le_bytes()).map_err(io)?;
        }
        for v in &o.crop.size {
            size.write_all(&v.to_le_bytes()).map_err(io)?;
        }
        let class = o.class.expect("labelled");
        label.write_all(&[class]).map_err(io)?;
        source.write_all(&[o.source]).map_err(io)?;
        per_class[class as usize] += 1;
    }
    for f in [&mut crop, &mut size, &mut label, &mut source] {
        f.flush().map_err(io)?;
    }
    let meta = serde_json::json!({
        "generator": "gen-recogniser-data",
        "seed": args.seed,
        "scenes": n,
        "unseen": args.unseen,
        "objects_placed": scenes.iter().map(|s| s.placed).sum::<usize>(),
        "segments_mixed": scenes.iter().map(SceneCrops::mixed).sum::<usize>(),
        "crops": m,
        "classes": classes,
        "per_class": classes.iter().zip(&per_class)
            .map(|(c, k)| (c.clone(), serde_json::json!(k)))
            .collect::<serde_json::Map<_, _>>(),
        "seconds": started.elapsed().as_secs_f64(),
    });
    std::fs::write(
        out.join("meta.json"),
        serde_json::to_string_pretty(&meta).map_err(|e| e.to_string())? + "\n",
    )
    .map_err(|e| e.to_string())?;
    eprintln!(
        "{m} crops from {n} scenes in {:.0} s -> {}",
        started.elapsed().as_secs_f64(),
        out.display()
    );
    Ok(())
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("gen-recogniser-data: {e}");
            ExitCode::FAILURE
        }
    }
}
