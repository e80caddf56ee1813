//! Tactile calibrations on disk (issue 16): one JSON file per calibration,
//! `CALIBRATIONS_DIR/NAME.json`, written to `.tmp-NAME-PID-N.json` first and renamed over the
//! old file in one step (atomic on one file system): a reader sees the old calibration or the
//! new one, never half of either; a crash leaves at worst a `.tmp-*` file, which the next start
//! removes. Plain Rust, no transport types.

use graspd_core::tactile::Calibration;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

fn path_of(dir: &Path, name: &str) -> PathBuf {
    dir.join(format!("{name}.json"))
}

/// Writes `calibration` as `DIR/NAME.json`, replacing any old one atomically.
pub fn save(dir: &Path, calibration: &Calibration) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let text = serde_json::to_vec(calibration).map_err(|e| e.to_string())?;
    let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp = dir.join(format!(
        ".tmp-{}-{}-{n}.json",
        calibration.name,
        std::process::id()
    ));
    let written = std::fs::write(&tmp, text)
        .and_then(|_| std::fs::rename(&tmp, path_of(dir, &calibration.name)));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(format!("{}: {e}", dir.display()));
    }
    Ok(())
}

/// Removes `DIR/NAME.json`.
pub fn remove(dir: &Path, name: &str) -> Result<(), String> {
    std::fs::remove_file(path_of(dir, name)).map_err(|e| format!("{}: {e}", dir.display()))
}

/// Every calibration of `dir` (created when missing), sorted by name; leftover `.tmp-*` files
/// are removed. A file that does not parse, or whose name is not its calibration's, is an error
/// naming it.
pub fn load_dir(dir: &Path) -> Result<Vec<Calibration>, String> {
    std::fs::create_dir_all(dir)
        .map_err(|e| format!("calibrations directory {}: {e}", dir.display()))?;
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("calibrations directory {}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    paths.sort();
    let mut out = Vec::new();
    for path in paths {
        let file = path
            .file_name()
            .and_then(|s| s.to_str())
            .unwrap_or_default();
        if file.starts_with(".tmp-") {
            let _ = std::fs::remove_file(&path);
            continue;
        }
        let Some(stem) = file.strip_suffix(".json") else {
            continue;
        };
        let bytes =
            std::fs::read(&path).map_err(|e| format!("calibration {}: {e}", path.display()))?;
        let c: Calibration = serde_json::from_slice(&bytes)
            .map_err(|e| format!("calibration {}: {e}", path.display()))?;
        if c.name != stem {
            return Err(format!(
                "calibration {}: the file holds calibration '{}'",
                path.display(),
                c.name
            ));
        }
        out.push(c);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use graspd_core::tactile::calibration::classifier::LinearDiscriminant;
    use graspd_core::tactile::{CalibrationSettings, CalibrationSummary};

    fn calibration(name: &str) -> Calibration {
        let examples: Vec<(String, Vec<f64>)> = [("foam", 0.1), ("foam", 0.3), ("metal", 2.0)]
            .iter()
            .map(|(c, v)| (c.to_string(), vec![*v, 1.0 / 3.0]))
            .collect();
        Calibration {
            name: name.into(),
            electrodes: 19,
            settings: CalibrationSettings::default(),
            material: Some(LinearDiscriminant::fit(&examples, "recordings").unwrap()),
            events: None,
            slip_direction: None,
            summary: CalibrationSummary {
                recordings: 3,
                material_windows: vec![("foam".into(), 2), ("metal".into(), 1)],
                event_windows: [0; 3],
                direction_windows: Vec::new(),
                fit_ms: 1.5,
            },
        }
    }

    /// Saved and loaded back bit for bit (the weights' floats round-trip); a leftover temporary
    /// file is removed at load; a replaced calibration is the new one; a file holding another
    /// name is refused naming the file.
    #[test]
    fn calibrations_round_trip_through_the_directory() {
        let dir = std::env::temp_dir().join(format!("graspd-cal-store-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let a = calibration("a");
        save(&dir, &a).unwrap();
        std::fs::write(dir.join(".tmp-b-1-0.json"), "{").unwrap();
        assert_eq!(load_dir(&dir).unwrap(), vec![a.clone()]);
        assert!(!dir.join(".tmp-b-1-0.json").exists());
        let mut a2 = calibration("a");
        a2.summary.recordings = 7;
        save(&dir, &a2).unwrap();
        assert_eq!(load_dir(&dir).unwrap(), vec![a2]);
        std::fs::copy(dir.join("a.json"), dir.join("c.json")).unwrap();
        let e = load_dir(&dir).unwrap_err();
        assert!(
            e.contains("c.json") && e.contains("holds calibration 'a'"),
            "{e}"
        );
        remove(&dir, "c").unwrap();
        remove(&dir, "a").unwrap();
        assert!(load_dir(&dir).unwrap().is_empty());
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A calibration stored before sensors that give only their electrodes and slip directions
    /// existed (no `electrodes_only`, `slip_direction` or `direction_windows`) loads as a
    /// BioTac calibration without a direction classifier.
    #[test]
    fn a_calibration_stored_by_an_older_server_still_loads() {
        let dir = std::env::temp_dir().join(format!("graspd-cal-old-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let a = calibration("old");
        save(&dir, &a).unwrap();
        let mut json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("old.json")).unwrap()).unwrap();
        let o = json.as_object_mut().unwrap();
        assert!(o.remove("slip_direction").is_some());
        assert!(
            o["settings"]
                .as_object_mut()
                .unwrap()
                .remove("electrodes_only")
                .is_some()
        );
        assert!(
            o["summary"]
                .as_object_mut()
                .unwrap()
                .remove("direction_windows")
                .is_some()
        );
        std::fs::write(dir.join("old.json"), json.to_string()).unwrap();
        assert_eq!(load_dir(&dir).unwrap(), vec![a]);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
