//! `eval-recogniser`: the recogniser's detection on held-out generated scenes, as graspd serves
//! `hints.object` (models/recogniser/MODEL_CARD.md): every segment of a scene is classified in
//! one batch, and each known object in view is named in turn (`find_named`); detection is
//! right when the chosen segment is that object. Every known object *not* in view is named
//! too: answering with any segment is a false detection (the service must say not found).
//!
//! ```text
//! eval-recogniser --model models/recogniser/recogniser.onnx --scenes 500 --seed 21 [--unseen]
//! ```
//! Prints a JSON report: detection rate (per class), false detections, segment accuracy and the
//! recogniser's time per scene.

use clap::Parser;
use graspd_core::perception::recognition::{RecognisedObject, RecognitionModel, find_named};
use graspd_model_data::recognition::{KNOWN, class_names, recognition_sample};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

#[derive(Parser, Debug)]
#[command(about = "Detection of named objects on held-out generated scenes")]
struct Args {
    #[arg(long)]
    model: PathBuf,
    #[arg(long, default_value_t = 500)]
    scenes: usize,
    /// A seed no training split used (train.sh: 11, 12, 13).
    #[arg(long, default_value_t = 21)]
    seed: u64,
    /// Add the chips can, never in training, as an unknown object.
    #[arg(long)]
    unseen: bool,
}

fn run(args: Args) -> Result<serde_json::Value, String> {
    let model = RecognitionModel::load(&args.model, 1).map_err(|e| e.to_string())?;
    let classes = class_names();
    if model.classes() != classes.as_slice() {
        return Err(format!(
            "the model's classes {:?} are not the generator's {classes:?}",
            model.classes()
        ));
    }
    let k = KNOWN.len();
    let (mut asked, mut found) = (vec![0usize; k], vec![0usize; k]);
    let (mut absent_asked, mut false_detections) = (0usize, 0usize);
    let (mut segments, mut segments_right) = (0usize, 0usize);
    let mut seconds = Vec::with_capacity(args.scenes);
    for i in 0..args.scenes {
        let s = recognition_sample(args.seed, i, args.unseen)?;
        let crops: Vec<_> = s.segments.iter().map(|o| o.crop.clone()).collect();
        let t = Instant::now();
        let probs = model.classify(&crops).map_err(|e| e.to_string())?;
        seconds.push(t.elapsed().as_secs_f64());
        let recognised: Vec<RecognisedObject> = probs
            .into_iter()
            .map(|p| {
                let best = (0..p.len())
                    .max_by(|&a, &b| p[a].total_cmp(&p[b]))
                    .unwrap_or(0);
                RecognisedObject {
                    class: classes[best].clone(),
                    probability: p[best],
                    pixel_centroid: [0.0; 2],
                    points: 0,
                    probabilities: p,
                }
            })
            .collect();
        for (seg, r) in s.segments.iter().zip(&recognised) {
            if let Some(c) = seg.class {
                segments += 1;
                segments_right += usize::from(r.class == classes[c as usize]);
            }
        }
        for (c, name) in classes[..k].iter().enumerate() {
            let present = s.segments.iter().any(|seg| seg.class == Some(c as u8));
            let answer = find_named(name, &classes, &recognised);
            if present {
                asked[c] += 1;
                found[c] += usize::from(answer.is_ok_and(|j| s.segments[j].class == Some(c as u8)));
            } else {
                absent_asked += 1;
                false_detections += usize::from(answer.is_ok());
            }
        }
    }
    seconds.sort_by(f64::total_cmp);
    let total_asked: usize = asked.iter().sum();
    let total_found: usize = found.iter().sum();
    Ok(serde_json::json!({
        "model": args.model.display().to_string(),
        "seed": args.seed,
        "scenes": args.scenes,
        "unseen": args.unseen,
        "detection": total_found as f64 / total_asked.max(1) as f64,
        "named_in_view": total_asked,
        "detection_per_class": classes[..k].iter().enumerate()
            .map(|(c, n)| (n.clone(), serde_json::json!(found[c] as f64 / asked[c].max(1) as f64)))
            .collect::<serde_json::Map<_, _>>(),
        "named_not_in_view": absent_asked,
        "false_detections": false_detections as f64 / absent_asked.max(1) as f64,
        "segment_accuracy": segments_right as f64 / segments.max(1) as f64,
        "segments": segments,
        "recogniser_ms_per_scene_p50": 1e3 * seconds.get(seconds.len() / 2).copied().unwrap_or(0.0),
    }))
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(report) => {
            println!(
                "{}",
                serde_json::to_string_pretty(&report).unwrap_or_default()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("eval-recogniser: {e}");
            ExitCode::FAILURE
        }
    }
}
