//! Reader for the CSV layout of the real BioTac recordings (`../shared/testdata/tactile/
//! biotac_slide`, dexrob/BioTac_slide_20_50): `_bio.csv` BioTac frames and the robot arm's
//! `_cw.csv` wrench and `_cv.csv` Cartesian velocity, from which per-frame ground-truth labels
//! are derived. Used by the tests and by the REST analyze endpoint.
//!
//! * `_bio.csv`: header `timestamp,tdc,tac,pdc,pac1..pac22,ele1..ele19`; every data row ends with
//!   a trailing comma (one empty field more than the header), which is ignored. Columns are found
//!   by name, so other electrode counts (`ele1..eleN`) and pac counts work too.
//! * An electrodes-only file (a sensor that gives only its electrodes, such as the BioTac SP
//!   recordings of yayaneath/BioTacSP-DoS, header `ff_e1..ff_e24`): a file without a `pdc`
//!   column. Its electrodes are the `ele1..eleN` columns when there are any, else every column
//!   but `timestamp`, in file order; pdc, tdc and tac read 0 and there is no pac. Without a
//!   `timestamp` column the rows are taken 10 ms apart (100 Hz) and cannot be aligned with the
//!   arm's files.
//! * `_cw.csv` `timestamp,fx,fy,fz,tx,ty,tz` and `_cv.csv` `timestamp,x,y,z,a,b,c` run at about
//!   150 Hz on their own clocks (`-nan` allowed); they are linearly interpolated onto the BioTac
//!   time stamps (held constant outside their time range).
//!
//! # Labels
//! * contact ⇔ the wrench's normal force fz ≥ `contact_force` (default 0.5 N; the F/T reading is
//!   not zeroed upstream, its no-contact level is around 0 ± 1.5 N and the pressed level ≈ 2.6 N);
//! * slip ⇔ contact and the arm's planar speed √(x² + y²) ≥ `slip_speed` (default 0.005, i.e.
//!   5 mm/s if the velocity is in m/s as it appears): the sensor slides over the fixed material, so
//!   the arm's velocity is the relative velocity;
//! * otherwise non-contact.

use super::detector::ContactEvent;
use super::readings::{FingerReading, Frame};
use crate::error::FieldError;

/// One `_bio.csv` row.
#[derive(Debug, Clone, PartialEq)]
pub struct BioRow {
    pub timestamp: f64,
    pub tdc: f64,
    pub tac: f64,
    pub pdc: f64,
    pub pac: Vec<f64>,
    pub electrodes: Vec<f64>,
}

impl BioRow {
    pub fn reading(&self) -> FingerReading {
        FingerReading {
            pdc: self.pdc,
            pac: self.pac.clone(),
            tdc: self.tdc,
            tac: self.tac,
            electrodes: self.electrodes.clone(),
        }
    }
}

/// A time series from a CSV with a `timestamp` column: the time stamps and the named columns.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub timestamps: Vec<f64>,
    /// `columns[c][i]`: column c at row i.
    pub columns: Vec<Vec<f64>>,
}

/// Splits CSV text into a header and rows of numbers (ignoring one trailing empty field).
/// `what` names the input in errors (e.g. `bio_csv`).
fn parse_numeric_csv(text: &str, what: &str) -> Result<(Vec<String>, Vec<Vec<f64>>), FieldError> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines
        .next()
        .ok_or_else(|| FieldError::new(what, "empty: no header line"))?;
    let mut names: Vec<String> = header.split(',').map(|s| s.trim().to_string()).collect();
    if names.last().is_some_and(|s| s.is_empty()) {
        names.pop();
    }
    let mut rows = Vec::new();
    for (i, line) in lines {
        let mut fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() == names.len() + 1 && fields.last() == Some(&"") {
            fields.pop();
        }
        if fields.len() != names.len() {
            return Err(FieldError::new(
                what,
                format!(
                    "line {}: {} values for {} header names",
                    i + 1,
                    fields.len(),
                    names.len()
                ),
            ));
        }
        let row = fields
            .iter()
            .zip(&names)
            .map(|(f, n)| {
                f.parse::<f64>().map_err(|_| {
                    FieldError::new(
                        what,
                        format!("line {}, column {n}: not a number: '{f}'", i + 1),
                    )
                })
            })
            .collect::<Result<Vec<f64>, _>>()?;
        rows.push(row);
    }
    Ok((names, rows))
}

fn column(names: &[String], name: &str, what: &str) -> Result<usize, FieldError> {
    names
        .iter()
        .position(|n| n.eq_ignore_ascii_case(name))
        .ok_or_else(|| FieldError::new(what, format!("no '{name}' column")))
}

/// Numbered columns `prefix1..prefixN` in order.
fn numbered(names: &[String], prefix: &str) -> Vec<usize> {
    let mut out = Vec::new();
    for k in 1.. {
        match names
            .iter()
            .position(|n| n.eq_ignore_ascii_case(&format!("{prefix}{k}")))
        {
            Some(i) => out.push(i),
            None => break,
        }
    }
    out
}

/// A parsed `_bio.csv` file: its rows and how it was laid out (module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct BioFile {
    pub rows: Vec<BioRow>,
    /// Only electrode columns (no `pdc`): pdc, tdc and tac are 0 and there is no pac.
    pub electrodes_only: bool,
    /// The file had a `timestamp` column (else the rows are 10 ms apart).
    pub timestamped: bool,
}

/// Row spacing assumed for a file without time stamps, s (100 Hz, a BioTac's frame rate).
pub const UNTIMED_ROW_S: f64 = 0.01;

/// Parses a `_bio.csv` file (module doc).
pub fn parse_bio_csv(text: &str) -> Result<Vec<BioRow>, FieldError> {
    parse_bio_file(text).map(|f| f.rows)
}

/// Parses a `_bio.csv` file of either layout (module doc).
pub fn parse_bio_file(text: &str) -> Result<BioFile, FieldError> {
    const WHAT: &str = "bio_csv";
    let (names, rows) = parse_numeric_csv(text, WHAT)?;
    let named = |want: &str| {
        names
            .iter()
            .any(|n| n.to_ascii_lowercase().starts_with(want))
    };
    if !named("pdc") {
        // A BioTac file that lost its pdc column is not an electrodes-only one: its thermal
        // and pac columns would be read as electrodes.
        if let Some(other) = ["tdc", "tac", "pac"].into_iter().find(|c| named(c)) {
            return Err(FieldError::new(
                WHAT,
                format!(
                    "a '{other}' column but no 'pdc': a BioTac file needs pdc, an electrodes-only \
                     file has only electrode columns (and timestamp)"
                ),
            ));
        }
        return electrodes_only_file(&names, rows);
    }
    let ts = column(&names, "timestamp", WHAT)?;
    let (tdc, tac, pdc) = (
        column(&names, "tdc", WHAT)?,
        column(&names, "tac", WHAT)?,
        column(&names, "pdc", WHAT)?,
    );
    let mut pac = numbered(&names, "pac");
    if pac.is_empty() {
        pac.push(column(&names, "pac", WHAT)?);
    }
    let ele = numbered(&names, "ele");
    if ele.is_empty() {
        return Err(FieldError::new(WHAT, "no electrode columns ele1..eleN"));
    }
    let rows = rows
        .into_iter()
        .map(|r| BioRow {
            timestamp: r[ts],
            tdc: r[tdc],
            tac: r[tac],
            pdc: r[pdc],
            pac: pac.iter().map(|&i| r[i]).collect(),
            electrodes: ele.iter().map(|&i| r[i]).collect(),
        })
        .collect();
    Ok(BioFile {
        rows,
        electrodes_only: false,
        timestamped: true,
    })
}

/// An electrodes-only file (module doc).
fn electrodes_only_file(names: &[String], rows: Vec<Vec<f64>>) -> Result<BioFile, FieldError> {
    let ts = names
        .iter()
        .position(|n| n.eq_ignore_ascii_case("timestamp"));
    let mut ele = numbered(names, "ele");
    if ele.is_empty() {
        ele = (0..names.len()).filter(|&i| Some(i) != ts).collect();
    }
    if ele.is_empty() {
        return Err(FieldError::new(
            "bio_csv",
            "no electrode columns (ele1..eleN, or any column but timestamp)",
        ));
    }
    let rows = rows
        .into_iter()
        .enumerate()
        .map(|(k, r)| BioRow {
            timestamp: ts.map_or(k as f64 * UNTIMED_ROW_S, |t| r[t]),
            tdc: 0.0,
            tac: 0.0,
            pdc: 0.0,
            pac: Vec::new(),
            electrodes: ele.iter().map(|&i| r[i]).collect(),
        })
        .collect();
    Ok(BioFile {
        rows,
        electrodes_only: true,
        timestamped: ts.is_some(),
    })
}

/// Parses a `_cw.csv` / `_cv.csv` file and picks the named columns.
pub fn parse_series_csv(text: &str, what: &str, wanted: &[&str]) -> Result<Series, FieldError> {
    let (names, rows) = parse_numeric_csv(text, what)?;
    let ts = column(&names, "timestamp", what)?;
    let idx = wanted
        .iter()
        .map(|w| column(&names, w, what))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Series {
        timestamps: rows.iter().map(|r| r[ts]).collect(),
        columns: idx
            .iter()
            .map(|&c| rows.iter().map(|r| r[c]).collect())
            .collect(),
    })
}

/// Linear interpolation of (t, v) at `at` (time stamps ascending; constant outside). Non-finite
/// samples are skipped.
pub fn interpolate(t: &[f64], v: &[f64], at: f64) -> f64 {
    let pts: Vec<(f64, f64)> = t
        .iter()
        .zip(v)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a, *b))
        .collect();
    if pts.is_empty() {
        return f64::NAN;
    }
    let i = pts.partition_point(|p| p.0 <= at);
    if i == 0 {
        return pts[0].1;
    }
    if i == pts.len() {
        return pts[i - 1].1;
    }
    let (a, b) = (pts[i - 1], pts[i]);
    if b.0 - a.0 <= 0.0 {
        return a.1;
    }
    a.1 + (b.1 - a.1) * (at - a.0) / (b.0 - a.0)
}

/// Thresholds of the labels (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LabelThresholds {
    /// Normal force for contact, N.
    pub contact_force: f64,
    /// Planar speed for slip (velocity units of `_cv.csv`).
    pub slip_speed: f64,
}

impl Default for LabelThresholds {
    fn default() -> Self {
        Self {
            contact_force: 0.5,
            slip_speed: 0.005,
        }
    }
}

/// One recording: BioTac rows and, when the arm's files were given, a label per row.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    pub rows: Vec<BioRow>,
    pub labels: Option<Vec<ContactEvent>>,
    /// The file gave only electrodes ([`BioFile::electrodes_only`]).
    pub electrodes_only: bool,
}

impl Recording {
    /// From the text of `_bio.csv` and optionally `_cw.csv` and `_cv.csv` (labels need both).
    pub fn from_csv(bio: &str, cw: Option<&str>, cv: Option<&str>) -> Result<Self, FieldError> {
        Self::from_csv_with(bio, cw, cv, LabelThresholds::default())
    }

    pub fn from_csv_with(
        bio: &str,
        cw: Option<&str>,
        cv: Option<&str>,
        th: LabelThresholds,
    ) -> Result<Self, FieldError> {
        let BioFile {
            rows,
            electrodes_only,
            timestamped,
        } = parse_bio_file(bio)?;
        if rows.is_empty() {
            return Err(FieldError::new("bio_csv", "no data rows"));
        }
        let labels = match (cw, cv) {
            (Some(_), Some(_)) if !timestamped => {
                return Err(FieldError::new(
                    "cw_csv",
                    "the bio_csv has no timestamp column to align the arm's files with",
                ));
            }
            (Some(cw), Some(cv)) => {
                let w = parse_series_csv(cw, "cw_csv", &["fz"])?;
                let v = parse_series_csv(cv, "cv_csv", &["x", "y"])?;
                Some(
                    rows.iter()
                        .map(|r| {
                            let fz = interpolate(&w.timestamps, &w.columns[0], r.timestamp);
                            let vx = interpolate(&v.timestamps, &v.columns[0], r.timestamp);
                            let vy = interpolate(&v.timestamps, &v.columns[1], r.timestamp);
                            // A NaN force (no wrench samples) is non-contact.
                            if fz.is_nan() || fz < th.contact_force {
                                ContactEvent::NonContact
                            } else if vx.hypot(vy) >= th.slip_speed {
                                ContactEvent::Slip
                            } else {
                                ContactEvent::Contact
                            }
                        })
                        .collect(),
                )
            }
            _ => None,
        };
        Ok(Self {
            rows,
            labels,
            electrodes_only,
        })
    }

    /// The rows as single-finger frames.
    pub fn frames(&self) -> Vec<Frame> {
        self.rows
            .iter()
            .map(|r| Frame {
                timestamp: r.timestamp,
                fingers: vec![r.reading()],
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BIO: &str = "timestamp,tdc,tac,pdc,pac1,pac2,ele1,ele2,ele3\n\
        10.00,1,2,3,4,5,6,7,8,\n\
        10.01,1,2,30,4,6,60,7,8,\n";

    #[test]
    fn bio_csv_with_trailing_commas_parses_by_column_name() {
        let rows = parse_bio_csv(BIO).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[1].pdc, 30.0);
        assert_eq!(rows[1].pac, vec![4.0, 6.0]);
        assert_eq!(rows[1].electrodes, vec![60.0, 7.0, 8.0]);
        let e = parse_bio_csv("timestamp,tdc,tac,pdc,pac,ele1\n1,2,3,4,5\n").unwrap_err();
        assert_eq!(e.field, "bio_csv");
        assert!(e.message.contains("line 2"), "{e}");
        let e = parse_bio_csv("timestamp,tdc,tac,pdc,pac,ele1\n1,2,3,x,5,6\n").unwrap_err();
        assert!(e.message.contains("column pdc"), "{e}");
    }

    /// A file without pdc is electrodes only: `ele` columns when named so, else every column
    /// but the time stamp; without time stamps the rows are 10 ms apart and cannot take the
    /// arm's files.
    #[test]
    fn an_electrodes_only_file_reads_its_electrodes() {
        let f = parse_bio_file("ff_e1,ff_e2,ff_e3\n3000,2900,2800\n2990,2890,2810\n").unwrap();
        assert!(f.electrodes_only && !f.timestamped);
        assert_eq!(f.rows[1].electrodes, vec![2990.0, 2890.0, 2810.0]);
        assert_eq!((f.rows[0].timestamp, f.rows[1].timestamp), (0.0, 0.01));
        assert!(f.rows[1].pac.is_empty() && f.rows[1].pdc == 0.0);
        let f = parse_bio_file("timestamp,ele1,ele2,note\n5.5,1,2,9\n").unwrap();
        assert!(f.electrodes_only && f.timestamped);
        assert_eq!(
            (f.rows[0].timestamp, &f.rows[0].electrodes[..]),
            (5.5, &[1.0, 2.0][..])
        );
        let cw = "timestamp,fx,fy,fz,tx,ty,tz\n0,0,0,3,0,0,0\n";
        let cv = "timestamp,x,y,z,a,b,c\n0,0,0,0,0,0,0\n";
        let e = Recording::from_csv("e1,e2\n1,2\n", Some(cw), Some(cv)).unwrap_err();
        assert_eq!(e.field, "cw_csv");
        let e = parse_bio_file("timestamp\n1\n").unwrap_err();
        assert!(e.message.contains("no electrode columns"), "{e}");
        // A BioTac file without its pdc column is refused, not read as electrodes.
        let e = parse_bio_file("timestamp,tdc,tac,pac1,ele1\n1,2,3,4,5\n").unwrap_err();
        assert!(e.message.contains("a 'tdc' column but no 'pdc'"), "{e}");
        assert!(
            !Recording::from_csv(BIO, None, None)
                .unwrap()
                .electrodes_only
        );
    }

    #[test]
    fn labels_come_from_interpolated_wrench_and_velocity() {
        let cw = "timestamp,fx,fy,fz,tx,ty,tz\n9.99,0,0,0,0,0,0\n10.02,0,0,3,0,0,0\n";
        let cv =
            "timestamp,x,y,z,a,b,c\n9.99,0,0,0,-nan,-nan,-nan\n10.02,0.03,0.0,0,-nan,-nan,-nan\n";
        let r = Recording::from_csv(BIO, Some(cw), Some(cv)).unwrap();
        // At 10.00: fz = 1 (≥ 0.5), speed 0.01 → slip. Check via the interpolation itself too.
        assert!((interpolate(&[9.99, 10.02], &[0.0, 3.0], 10.0) - 1.0).abs() < 1e-9);
        assert_eq!(
            r.labels.unwrap(),
            vec![ContactEvent::Slip, ContactEvent::Slip]
        );
        let cw0 = "timestamp,fx,fy,fz,tx,ty,tz\n9.99,0,0,0,0,0,0\n10.5,0,0,0.1,0,0,0\n";
        let r = Recording::from_csv(BIO, Some(cw0), Some(cv)).unwrap();
        assert_eq!(r.labels.as_ref().unwrap()[0], ContactEvent::NonContact);
        assert_eq!(r.frames().len(), 2);
    }
}
