//! The one tactile-sensor layout type of graspd (method.md §5, dissertation Fig 6.5): a sensor's
//! electrode centres (x, y in mm) and where each electrode lands in the 8 × 5 tactile image.
//!
//! Built-in layouts (classic BioTac, 19 electrodes; BioTac SP, 24) are data files in
//! `service/sensors/`, embedded at compile time. A custom layout is just the electrode
//! coordinates; its image mapping is derived the same way as for the built-ins:
//!
//! * **Rows** (8) bin the x coordinate (along the finger), row 0 at the smallest x; **columns**
//!   (5) bin y (across the finger), column 0 at the smallest y. Each axis is divided into equal
//!   bins spanning [min, max] of the electrodes.
//! * **Collisions** (two electrodes in one bin) are resolved deterministically: electrodes are
//!   placed in index order, and one whose bin is taken goes to the free pixel nearest (Euclidean, in
//!   pixel units) to its continuous bin position; ties go to the smaller (row, col).
//!
//! The pixel pitch (bin size in mm along x and y) gives contact areas in mm².

use crate::error::FieldError;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Rows of the tactile image (along the finger, x).
pub const IMAGE_ROWS: usize = 8;
/// Columns of the tactile image (across the finger, y).
pub const IMAGE_COLS: usize = 5;
/// The most electrodes a layout may have (one per pixel).
pub const MAX_ELECTRODES: usize = IMAGE_ROWS * IMAGE_COLS;

/// The data-file / request form of a layout: a name and the electrode coordinates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayoutSpec {
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// `electrodes[i] = [x_mm, y_mm]` of electrode i+1.
    pub electrodes: Vec<[f64; 2]>,
}

/// A validated layout with its derived image mapping.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SensorLayout {
    pub name: String,
    pub description: String,
    /// Electrode centres, mm.
    pub electrodes: Vec<[f64; 2]>,
    /// `pixels[i] = (row, col)` of electrode i in the 8 × 5 image.
    pub pixels: Vec<(usize, usize)>,
    /// Bin size along x (rows) and y (columns), mm.
    pub pixel_pitch_mm: [f64; 2],
}

impl SensorLayout {
    /// Validates electrode coordinates and derives the image mapping. Errors name the field
    /// (`layout.electrodes[3]`, …).
    pub fn from_spec(spec: LayoutSpec) -> Result<Self, FieldError> {
        let name = spec.name.trim();
        if name.is_empty() || name.len() > 64 {
            return Err(FieldError::new("layout.name", "must be 1 to 64 characters"));
        }
        if !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.')
        {
            return Err(FieldError::new(
                "layout.name",
                "may contain only ASCII letters, digits, '_', '-' and '.'",
            ));
        }
        let n = spec.electrodes.len();
        if !(2..=MAX_ELECTRODES).contains(&n) {
            return Err(FieldError::new(
                "layout.electrodes",
                format!("must list 2 to {MAX_ELECTRODES} electrodes, got {n}"),
            ));
        }
        for (i, p) in spec.electrodes.iter().enumerate() {
            if !p[0].is_finite() || !p[1].is_finite() || p[0].abs() > 1000.0 || p[1].abs() > 1000.0
            {
                return Err(FieldError::new(
                    format!("layout.electrodes[{i}]"),
                    format!("coordinates must be finite mm within ±1000, got {p:?}"),
                ));
            }
            for (j, q) in spec.electrodes[..i].iter().enumerate() {
                if (p[0] - q[0]).hypot(p[1] - q[1]) < 1e-6 {
                    return Err(FieldError::new(
                        format!("layout.electrodes[{i}]"),
                        format!("same position as electrodes[{j}]"),
                    ));
                }
            }
        }
        let (pixels, pitch) = bin_electrodes(&spec.electrodes);
        Ok(Self {
            name: name.to_string(),
            description: spec.description,
            electrodes: spec.electrodes,
            pixels,
            pixel_pitch_mm: pitch,
        })
    }

    /// A custom layout from electrode coordinates (mm).
    pub fn custom(name: &str, electrodes: Vec<[f64; 2]>) -> Result<Self, FieldError> {
        Self::from_spec(LayoutSpec {
            name: name.to_string(),
            description: String::new(),
            electrodes,
        })
    }

    pub fn electrode_count(&self) -> usize {
        self.electrodes.len()
    }

    /// Area of one image pixel, mm².
    pub fn pixel_area_mm2(&self) -> f64 {
        self.pixel_pitch_mm[0] * self.pixel_pitch_mm[1]
    }

    /// The classic BioTac (19 electrodes).
    pub fn biotac() -> Self {
        SensorCatalog::builtin().get("biotac").unwrap().clone()
    }

    /// The BioTac SP (24 electrodes).
    pub fn biotac_sp() -> Self {
        SensorCatalog::builtin().get("biotac_sp").unwrap().clone()
    }
}

/// Bins electrode coordinates into the 8 × 5 grid (see the module doc). Returns the pixel of
/// each electrode and the pitch (mm per bin along x, y).
fn bin_electrodes(e: &[[f64; 2]]) -> (Vec<(usize, usize)>, [f64; 2]) {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in e {
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let bins = [IMAGE_ROWS as f64, IMAGE_COLS as f64];
    // A degenerate axis (all electrodes on one line) maps to the middle bin with a 1 mm pitch.
    let span = [hi[0] - lo[0], hi[1] - lo[1]];
    let pitch = [0, 1].map(|a| {
        if span[a] > 1e-9 {
            span[a] / bins[a]
        } else {
            1.0
        }
    });
    // Continuous bin coordinate in [0, bins], bin = floor, clamped.
    let cont = |p: &[f64; 2], a: usize| -> f64 {
        if span[a] > 1e-9 {
            (p[a] - lo[a]) / span[a] * bins[a]
        } else {
            bins[a] / 2.0
        }
    };
    let mut taken = [[false; IMAGE_COLS]; IMAGE_ROWS];
    let mut out = Vec::with_capacity(e.len());
    for p in e {
        let (cr, cc) = (cont(p, 0), cont(p, 1));
        let r = (cr.floor() as usize).min(IMAGE_ROWS - 1);
        let c = (cc.floor() as usize).min(IMAGE_COLS - 1);
        let cell = if !taken[r][c] {
            (r, c)
        } else {
            // Nearest free pixel centre to the continuous position; ties → smaller (row, col).
            let mut best = (f64::INFINITY, (0, 0));
            for (rr, row) in taken.iter().enumerate() {
                for (ccol, &t) in row.iter().enumerate() {
                    if t {
                        continue;
                    }
                    let d = (rr as f64 + 0.5 - cr.min(bins[0] - 0.5))
                        .hypot(ccol as f64 + 0.5 - cc.min(bins[1] - 0.5));
                    if d < best.0 - 1e-12 {
                        best = (d, (rr, ccol));
                    }
                }
            }
            best.1
        };
        taken[cell.0][cell.1] = true;
        out.push(cell);
    }
    (out, pitch)
}

/// The built-in sensor layouts, embedded at compile time.
const BUILTIN_FILES: [(&str, &str); 2] = [
    ("biotac.toml", include_str!("../../../sensors/biotac.toml")),
    (
        "biotac_sp.toml",
        include_str!("../../../sensors/biotac_sp.toml"),
    ),
];

/// Parses and validates a layout written in TOML (the format of the data files).
pub fn parse_layout_toml(text: &str) -> Result<SensorLayout, FieldError> {
    let spec: LayoutSpec =
        toml::from_str(text).map_err(|e| FieldError::new("layout", e.to_string()))?;
    SensorLayout::from_spec(spec)
}

/// Sensor layouts by name.
#[derive(Debug, Clone, Default)]
pub struct SensorCatalog {
    layouts: BTreeMap<String, SensorLayout>,
}

impl SensorCatalog {
    /// The built-in layouts. Panics only if a shipped data file is invalid, which the unit tests
    /// rule out.
    pub fn builtin() -> Self {
        let mut c = Self::default();
        for (file, text) in BUILTIN_FILES {
            let l = parse_layout_toml(text)
                .unwrap_or_else(|e| panic!("built-in sensor file {file} is invalid: {e}"));
            c.layouts.insert(l.name.clone(), l);
        }
        c
    }

    pub fn get(&self, name: &str) -> Option<&SensorLayout> {
        self.layouts.get(name)
    }

    pub fn names(&self) -> Vec<String> {
        self.layouts.keys().cloned().collect()
    }

    pub fn insert(&mut self, layout: SensorLayout) {
        self.layouts.insert(layout.name.clone(), layout);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_injective(l: &SensorLayout) {
        let mut seen = std::collections::BTreeSet::new();
        for &(r, c) in &l.pixels {
            assert!(r < IMAGE_ROWS && c < IMAGE_COLS);
            assert!(
                seen.insert((r, c)),
                "{}: pixel ({r},{c}) used twice",
                l.name
            );
        }
    }

    #[test]
    fn builtin_layouts_load_with_their_electrode_counts() {
        let c = SensorCatalog::builtin();
        assert_eq!(c.names(), ["biotac", "biotac_sp"]);
        let b = c.get("biotac").unwrap();
        assert_eq!(b.electrode_count(), 19);
        assert_injective(b);
        let sp = c.get("biotac_sp").unwrap();
        assert_eq!(sp.electrode_count(), 24);
        assert_injective(sp);
        // Classic BioTac: x spans −13.6…4.763 mm over 8 rows, y ±4.956 mm over 5 columns.
        assert!((b.pixel_pitch_mm[0] - 18.363 / 8.0).abs() < 1e-9);
        assert!((b.pixel_pitch_mm[1] - 9.912 / 5.0).abs() < 1e-9);
        // E7 (the tip, largest x, y = 0) is in the last row, middle column; E19 (smallest x, y = 0)
        // in the first row, middle column.
        assert_eq!(b.pixels[6], (7, 2));
        assert_eq!(b.pixels[18], (0, 2));
        // Mirror electrodes E1 / E11 sit in the outer columns of the same row.
        assert_eq!(b.pixels[0].0, b.pixels[10].0);
        assert_eq!((b.pixels[0].1, b.pixels[10].1), (0, 4));
    }

    #[test]
    fn custom_layout_binning_and_deterministic_collisions() {
        // A 2 × 2 square spanning [0, 8] × [0, 5] mm: corners go to the corner pixels.
        let l = SensorLayout::custom("sq", vec![[0.0, 0.0], [8.0, 0.0], [0.0, 5.0], [8.0, 5.0]])
            .unwrap();
        assert_eq!(l.pixels, vec![(0, 0), (7, 0), (0, 4), (7, 4)]);
        assert_eq!(l.pixel_pitch_mm, [1.0, 1.0]);
        // Two electrodes in one bin: the second moves to the nearest free pixel.
        let l = SensorLayout::custom("c", vec![[0.0, 0.0], [0.1, 0.1], [8.0, 5.0]]).unwrap();
        assert_eq!(l.pixels[0], (0, 0));
        assert_eq!(l.pixels[1], (0, 1)); // (0,1) and (1,0) equidistant → smaller (row, col)
        let again = SensorLayout::custom("c", vec![[0.0, 0.0], [0.1, 0.1], [8.0, 5.0]]).unwrap();
        assert_eq!(l, again);
    }

    #[test]
    fn layout_validation_errors_name_the_field() {
        let e = SensorLayout::custom("x", vec![[0.0, 0.0]]).unwrap_err();
        assert_eq!(e.field, "layout.electrodes");
        let e = SensorLayout::custom("x", vec![[0.0, 0.0], [1.0, f64::NAN]]).unwrap_err();
        assert_eq!(e.field, "layout.electrodes[1]");
        let e = SensorLayout::custom("x", vec![[0.0, 0.0], [1.0, 1.0], [0.0, 0.0]]).unwrap_err();
        assert_eq!(e.field, "layout.electrodes[2]");
        assert!(e.message.contains("electrodes[0]"));
        let e = SensorLayout::custom("bad name", vec![[0.0, 0.0], [1.0, 1.0]]).unwrap_err();
        assert_eq!(e.field, "layout.name");
        let e = SensorLayout::custom("x", vec![[0.0, 0.0]; 41]).unwrap_err();
        assert_eq!(e.field, "layout.electrodes");
        let e = parse_layout_toml("name = \"x\"\nelectrodes = [[0.0]]").unwrap_err();
        assert_eq!(e.field, "layout");
    }
}
