//! PCD (Point Cloud Library) files, `DATA ascii` and `DATA binary` (little-endian).
//! `binary_compressed` is recognised and refused with a clear error. See the module docs of
//! [`super`] for why this is hand-written.

use super::{
    CloudBuilder, Slot, bounded_capacity, check_writer_normals, error, normals_present,
    parse_number, show, split_header,
};
use crate::cloud::PointCloud;
use crate::error::FieldError;
use nalgebra::{Point3, Vector3};
use std::fmt::Write as _;

const KEYWORDS: [&str; 10] = [
    "VERSION",
    "FIELDS",
    "SIZE",
    "TYPE",
    "COUNT",
    "WIDTH",
    "HEIGHT",
    "VIEWPOINT",
    "POINTS",
    "DATA",
];

/// Whether `word` is a PCD header keyword (case-insensitive).
pub(super) fn is_keyword(word: &str) -> bool {
    KEYWORDS.iter().any(|k| k.eq_ignore_ascii_case(word))
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    F32,
    F64,
    I8,
    I16,
    I32,
    I64,
    U8,
    U16,
    U32,
    U64,
}

impl Kind {
    fn of(ty: &str, size: u64) -> Option<Kind> {
        Some(match (ty, size) {
            ("F", 4) => Kind::F32,
            ("F", 8) => Kind::F64,
            ("I", 1) => Kind::I8,
            ("I", 2) => Kind::I16,
            ("I", 4) => Kind::I32,
            ("I", 8) => Kind::I64,
            ("U", 1) => Kind::U8,
            ("U", 2) => Kind::U16,
            ("U", 4) => Kind::U32,
            ("U", 8) => Kind::U64,
            _ => return None,
        })
    }

    /// Reads one little-endian value; `b` holds at least the value's size (checked by the
    /// caller through the record layout); `None` if it does not.
    fn read_le(self, b: &[u8]) -> Option<f64> {
        fn arr<const N: usize>(b: &[u8]) -> Option<[u8; N]> {
            b.get(..N)?.try_into().ok()
        }
        Some(match self {
            Kind::F32 => f32::from_le_bytes(arr(b)?) as f64,
            Kind::F64 => f64::from_le_bytes(arr(b)?),
            Kind::I8 => i8::from_le_bytes(arr(b)?) as f64,
            Kind::I16 => i16::from_le_bytes(arr(b)?) as f64,
            Kind::I32 => i32::from_le_bytes(arr(b)?) as f64,
            Kind::I64 => i64::from_le_bytes(arr(b)?) as f64,
            Kind::U8 => u8::from_le_bytes(arr(b)?) as f64,
            Kind::U16 => u16::from_le_bytes(arr(b)?) as f64,
            Kind::U32 => u32::from_le_bytes(arr(b)?) as f64,
            Kind::U64 => u64::from_le_bytes(arr(b)?) as f64,
        })
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Data {
    Ascii,
    Binary,
}

#[derive(Debug)]
struct Field {
    name: String,
    kind: Kind,
    /// Bytes of one value.
    size: u64,
    count: u64,
}

#[derive(Debug)]
struct Header {
    fields: Vec<Field>,
    points: u64,
    data: Data,
    body_start: usize,
    /// Number of lines of the header (the body's first line is this + 1).
    lines: usize,
}

fn parse_u64(word: &str, what: &str, line: usize) -> Result<u64, FieldError> {
    word.parse::<u64>().map_err(|_| {
        error(format!(
            "PCD: header line {line}: {what} value \"{}\" is not a non-negative integer",
            show(word.as_bytes())
        ))
    })
}

fn single_u64(rest: &[&str], what: &str, line: usize) -> Result<u64, FieldError> {
    match rest {
        [one] => parse_u64(one, what, line),
        _ => Err(error(format!(
            "PCD: header line {line}: {what} takes one value, found {}",
            rest.len()
        ))),
    }
}

fn parse_header(bytes: &[u8]) -> Result<Header, FieldError> {
    let (lines, body_start) = split_header(bytes, "PCD", "DATA", |l| {
        l.split_ascii_whitespace()
            .next()
            .is_some_and(|w| w.eq_ignore_ascii_case("DATA"))
    })?;
    let mut names: Option<Vec<String>> = None;
    let mut sizes: Option<Vec<u64>> = None;
    let mut types: Option<Vec<String>> = None;
    let mut counts: Option<Vec<u64>> = None;
    let (mut width, mut height, mut points) = (None, None, None);
    let mut data = None;
    for (no, text) in &lines {
        let no = *no;
        let text = text.trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let mut words = text.split_ascii_whitespace();
        let key = words.next().unwrap_or("").to_ascii_uppercase();
        let rest: Vec<&str> = words.collect();
        match key.as_str() {
            "VERSION" | "VIEWPOINT" => {}
            "FIELDS" => names = Some(rest.iter().map(|s| s.to_string()).collect()),
            "SIZE" => {
                sizes = Some(
                    rest.iter()
                        .map(|w| parse_u64(w, "SIZE", no))
                        .collect::<Result<_, _>>()?,
                )
            }
            "TYPE" => types = Some(rest.iter().map(|s| s.to_ascii_uppercase()).collect()),
            "COUNT" => {
                counts = Some(
                    rest.iter()
                        .map(|w| parse_u64(w, "COUNT", no))
                        .collect::<Result<_, _>>()?,
                )
            }
            "WIDTH" => width = Some(single_u64(&rest, "WIDTH", no)?),
            "HEIGHT" => height = Some(single_u64(&rest, "HEIGHT", no)?),
            "POINTS" => points = Some(single_u64(&rest, "POINTS", no)?),
            "DATA" => {
                data = Some(match rest.as_slice() {
                    [w] if w.eq_ignore_ascii_case("ascii") => Data::Ascii,
                    [w] if w.eq_ignore_ascii_case("binary") => Data::Binary,
                    [w] if w.eq_ignore_ascii_case("binary_compressed") => {
                        return Err(error(
                            "PCD: DATA binary_compressed is not supported; send DATA binary or \
                             DATA ascii (e.g. pcl_convert_pcd_ascii_binary <in> <out> 1)",
                        ));
                    }
                    _ => {
                        return Err(error(format!(
                            "PCD: header line {no}: DATA must be ascii or binary, found \"{}\"",
                            show(rest.join(" ").as_bytes())
                        )));
                    }
                })
            }
            _ => {
                return Err(error(format!(
                    "PCD: header line {no}: unknown keyword \"{}\"",
                    show(key.as_bytes())
                )));
            }
        }
    }
    // split_header stopped at the DATA line, so `data` is set.
    let data = data.ok_or_else(|| error("PCD: the header has no DATA line"))?;
    let names = names
        .filter(|n| !n.is_empty())
        .ok_or_else(|| error("PCD: the header has no FIELDS line (or it is empty)"))?;
    let sizes = sizes.ok_or_else(|| error("PCD: the header has no SIZE line"))?;
    let types = types.ok_or_else(|| error("PCD: the header has no TYPE line"))?;
    let counts = counts.unwrap_or_else(|| vec![1; names.len()]);
    for (what, len) in [
        ("SIZE", sizes.len()),
        ("TYPE", types.len()),
        ("COUNT", counts.len()),
    ] {
        if len != names.len() {
            return Err(error(format!(
                "PCD: FIELDS lists {} fields but {what} gives {len} values",
                names.len()
            )));
        }
    }
    let mut fields = Vec::with_capacity(names.len());
    for (((name, size), ty), count) in names.into_iter().zip(sizes).zip(types).zip(counts) {
        let kind = Kind::of(&ty, size).ok_or_else(|| {
            error(format!(
                "PCD: field {name} has TYPE {} with SIZE {size}; supported are F 4/8, I 1/2/4/8 \
                 and U 1/2/4/8",
                show(ty.as_bytes())
            ))
        })?;
        if count == 0 {
            return Err(error(format!("PCD: field {name} has COUNT 0")));
        }
        fields.push(Field {
            name,
            kind,
            size,
            count,
        });
    }
    let points = match (points, width) {
        (Some(p), Some(w)) => {
            let wh = w.checked_mul(height.unwrap_or(1));
            if wh != Some(p) {
                return Err(error(format!(
                    "PCD: POINTS {p} disagrees with WIDTH {w} x HEIGHT {}",
                    height.unwrap_or(1)
                )));
            }
            p
        }
        (Some(p), None) => p,
        (None, Some(w)) => w.checked_mul(height.unwrap_or(1)).ok_or_else(|| {
            error("PCD: WIDTH x HEIGHT overflows; the header's point count is not believable")
        })?,
        (None, None) => return Err(error("PCD: the header has neither POINTS nor WIDTH")),
    };
    Ok(Header {
        fields,
        points,
        data,
        body_start,
        lines: lines.len(),
    })
}

/// Reads a PCD file (`DATA ascii` or `DATA binary`): x, y, z and, when present, normal_x,
/// normal_y, normal_z. Never panics; errors name what is wrong.
pub fn read_pcd(bytes: &[u8]) -> Result<PointCloud, FieldError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let header = parse_header(bytes)?;
    // Where each slot's value is: (field index, element 0 of it).
    let mut slot_field: [Option<usize>; 6] = [None; 6];
    let mut slot_name: [Option<String>; 6] = Default::default();
    for (i, f) in header.fields.iter().enumerate() {
        if let Some(s) = Slot::of(&f.name)
            && slot_field[s.index()].is_none()
        {
            if f.count != 1 {
                return Err(error(format!(
                    "PCD: field {} has COUNT {}, expected 1",
                    f.name, f.count
                )));
            }
            slot_field[s.index()] = Some(i);
            slot_name[s.index()] = Some(f.name.clone());
        }
    }
    for (s, axis) in [(Slot::X, "x"), (Slot::Y, "y"), (Slot::Z, "z")] {
        if slot_field[s.index()].is_none() {
            return Err(error(format!("PCD: FIELDS has no field {axis}")));
        }
    }
    let with_normals = normals_present("PCD", &slot_name)?;
    let body = bytes.get(header.body_start..).unwrap_or(&[]);
    match header.data {
        Data::Binary => read_binary(&header, body, &slot_field, with_normals),
        Data::Ascii => read_ascii(&header, body, &slot_field, with_normals),
    }
}

fn read_binary(
    header: &Header,
    body: &[u8],
    slot_field: &[Option<usize>; 6],
    with_normals: bool,
) -> Result<PointCloud, FieldError> {
    // Record layout: byte offset of every field; sizes checked against overflow.
    let overflow = || error("PCD: the record size from SIZE x COUNT overflows");
    let mut offsets = Vec::with_capacity(header.fields.len());
    let mut record: u64 = 0;
    for f in &header.fields {
        offsets.push(record);
        let bytes = f.size.checked_mul(f.count).ok_or_else(overflow)?;
        record = record.checked_add(bytes).ok_or_else(overflow)?;
    }
    let record = usize::try_from(record).map_err(|_| overflow())?;
    // record >= 1: every field has SIZE >= 1 and COUNT >= 1.
    let found = body.len() / record.max(1);
    if header.points > found as u64 {
        return Err(error(format!(
            "PCD: DATA section truncated: header says {} points, found {found} ({} bytes of \
             {record}-byte records)",
            header.points,
            body.len()
        )));
    }
    let n = header.points as usize; // <= found, so it fits.
    let slots: Vec<(usize, usize, Kind)> = slot_field
        .iter()
        .enumerate()
        .filter_map(|(s, f)| {
            let f = (*f)?;
            Some((s, offsets[f] as usize, header.fields[f].kind))
        })
        .collect();
    let mut out = CloudBuilder::new(bounded_capacity(header.points, found), with_normals);
    for rec in body.chunks_exact(record.max(1)).take(n) {
        let mut v = [0.0f64; 6];
        for &(s, off, kind) in &slots {
            v[s] = rec
                .get(off..)
                .and_then(|b| kind.read_le(b))
                .ok_or_else(|| error("PCD: record layout does not fit the record size"))?;
        }
        out.push(&v);
    }
    Ok(out.finish())
}

fn read_ascii(
    header: &Header,
    body: &[u8],
    slot_field: &[Option<usize>; 6],
    with_normals: bool,
) -> Result<PointCloud, FieldError> {
    // Token index of each slot, and the number of tokens per point.
    let mut first_token = Vec::with_capacity(header.fields.len());
    let mut per_point: u64 = 0;
    for f in &header.fields {
        first_token.push(per_point);
        per_point = per_point
            .checked_add(f.count)
            .ok_or_else(|| error("PCD: the sum of COUNT overflows"))?;
    }
    let mut wanted: Vec<(u64, usize, &str)> = slot_field
        .iter()
        .enumerate()
        .filter_map(|(s, f)| {
            let f = (*f)?;
            Some((first_token[f], s, header.fields[f].name.as_str()))
        })
        .collect();
    wanted.sort_unstable();
    // Every point needs at least "a b c\n"-like bytes: two per token.
    let room = body.len() / (2 * per_point.clamp(1, 1 << 20) as usize);
    let mut out = CloudBuilder::new(bounded_capacity(header.points, room), with_normals);
    let mut found: u64 = 0;
    let mut line_no = header.lines;
    for raw in body.split(|&b| b == b'\n') {
        line_no += 1;
        if found == header.points {
            break;
        }
        let Ok(line) = std::str::from_utf8(raw) else {
            return Err(error(format!(
                "PCD: line {line_no} of the ascii data is not text"
            )));
        };
        if line.trim().is_empty() {
            continue;
        }
        let mut v = [0.0f64; 6];
        let mut next = wanted.iter().peekable();
        let mut k: u64 = 0;
        for tok in line.split_ascii_whitespace() {
            while let Some(&&(t, s, name)) = next.peek() {
                if t != k {
                    break;
                }
                v[s] = parse_number(tok.as_bytes()).ok_or_else(|| {
                    error(format!(
                        "PCD: point {found} (line {line_no}): value \"{}\" of field {name} is \
                         not a number",
                        show(tok.as_bytes())
                    ))
                })?;
                next.next();
            }
            k += 1;
        }
        if k != per_point {
            return Err(error(format!(
                "PCD: point {found} (line {line_no}) has {k} values, expected {per_point} \
                 (the sum of COUNT)"
            )));
        }
        out.push(&v);
        found += 1;
    }
    if found < header.points {
        return Err(error(format!(
            "PCD: DATA section truncated: header says {} points, found {found}",
            header.points
        )));
    }
    Ok(out.finish())
}

fn header_text(n: usize, with_normals: bool, data: &str) -> String {
    let (fields, sizes, types, counts) = if with_normals {
        (
            "x y z normal_x normal_y normal_z",
            "4 4 4 4 4 4",
            "F F F F F F",
            "1 1 1 1 1 1",
        )
    } else {
        ("x y z", "4 4 4", "F F F", "1 1 1")
    };
    format!(
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS {fields}\nSIZE {sizes}\n\
         TYPE {types}\nCOUNT {counts}\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\n\
         DATA {data}\n"
    )
}

/// Writes an ascii PCD (float32 x y z, plus normal_x/y/z when given).
///
/// # Panics
/// If `normals` is given with a length other than `points.len()` (a caller bug).
pub fn write_pcd_ascii(points: &[Point3<f64>], normals: Option<&[Vector3<f64>]>) -> Vec<u8> {
    check_writer_normals(points, normals);
    let mut s = header_text(points.len(), normals.is_some(), "ascii");
    for (i, p) in points.iter().enumerate() {
        let _ = write!(s, "{} {} {}", p.x as f32, p.y as f32, p.z as f32);
        if let Some(n) = normals {
            let n = &n[i];
            let _ = write!(s, " {} {} {}", n.x as f32, n.y as f32, n.z as f32);
        }
        s.push('\n');
    }
    s.into_bytes()
}

/// Writes a binary PCD (little-endian float32 x y z, plus normal_x/y/z when given).
///
/// # Panics
/// If `normals` is given with a length other than `points.len()` (a caller bug).
pub fn write_pcd_binary(points: &[Point3<f64>], normals: Option<&[Vector3<f64>]>) -> Vec<u8> {
    check_writer_normals(points, normals);
    let mut out = header_text(points.len(), normals.is_some(), "binary").into_bytes();
    let per = if normals.is_some() { 24 } else { 12 };
    out.reserve(points.len() * per);
    for (i, p) in points.iter().enumerate() {
        for v in p.coords.iter() {
            out.extend_from_slice(&(*v as f32).to_le_bytes());
        }
        if let Some(n) = normals {
            for v in n[i].iter() {
                out.extend_from_slice(&(*v as f32).to_le_bytes());
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(n: usize) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
        let pts = (0..n)
            .map(|i| {
                let t = i as f64 * 0.37;
                Point3::new(t.sin() * 0.05, t.cos() * 0.05 + 0.08, i as f64 * 1e-3)
            })
            .collect();
        let nrm = (0..n)
            .map(|i| {
                let t = i as f64 * 0.37;
                Vector3::new(t.sin(), t.cos(), 0.0)
            })
            .collect();
        (pts, nrm)
    }

    fn close(a: &[Point3<f64>], b: &[Point3<f64>]) {
        assert_eq!(a.len(), b.len());
        for (p, q) in a.iter().zip(b) {
            assert!((p - q).norm() < 1e-6, "{p} vs {q}");
        }
    }

    #[test]
    fn round_trips() {
        let (pts, nrm) = sample(300);
        for bytes in [write_pcd_ascii(&pts, None), write_pcd_binary(&pts, None)] {
            let c = read_pcd(&bytes).unwrap();
            close(&c.points, &pts);
            assert!(c.normals.is_none());
        }
        for bytes in [
            write_pcd_ascii(&pts, Some(&nrm)),
            write_pcd_binary(&pts, Some(&nrm)),
        ] {
            let c = read_pcd(&bytes).unwrap();
            close(&c.points, &pts);
            let n = c.normals.unwrap();
            for (a, b) in n.iter().zip(&nrm) {
                assert!((a - b).norm() < 1e-6);
            }
        }
        // Empty cloud: a valid file with no points.
        let c = read_pcd(&write_pcd_binary(&[], None)).unwrap();
        assert!(c.is_empty());
    }

    #[test]
    fn hand_written_ascii_with_comments_extra_fields_and_nan() {
        let text = "# a comment\n\
            VERSION .7\n\
            FIELDS x y z rgb normal_x normal_y normal_z curvature\n\
            SIZE 4 4 4 4 4 4 4 4\n\
            TYPE F F F U F F F F\n\
            COUNT 1 1 1 1 1 1 1 1\n\
            WIDTH 4\n\
            HEIGHT 1\n\
            VIEWPOINT 0 0 0 1 0 0 0\n\
            POINTS 4\n\
            DATA ascii\n\
            0.1 0.2 0.3 4286611584 0 0 1 0.01\n\
            \n\
            -1.5e-2 2 3.25 0 1 0 0 0\r\n\
            nan nan nan 0 nan nan nan 0\n\
            4 5 6 0 0 -1 0 0.5\n";
        let c = read_pcd(text.as_bytes()).unwrap();
        assert_eq!(
            c.points,
            vec![
                Point3::new(0.1, 0.2, 0.3),
                Point3::new(-0.015, 2.0, 3.25),
                Point3::new(4.0, 5.0, 6.0)
            ]
        );
        assert_eq!(
            c.normals.unwrap(),
            vec![
                Vector3::new(0.0, 0.0, 1.0),
                Vector3::new(1.0, 0.0, 0.0),
                Vector3::new(0.0, -1.0, 0.0)
            ]
        );
    }

    #[test]
    fn binary_with_doubles_and_padding() {
        // x y z as F8, a 3-byte U1 padding field, normals missing.
        let mut b = b"FIELDS x pad y z\nSIZE 8 1 8 8\nTYPE F U F F\nCOUNT 1 3 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n".to_vec();
        for (x, y, z) in [(1.0f64, 2.0f64, 3.0f64), (-4.0, 5.5, 0.25)] {
            b.extend_from_slice(&x.to_le_bytes());
            b.extend_from_slice(&[9, 9, 9]);
            b.extend_from_slice(&y.to_le_bytes());
            b.extend_from_slice(&z.to_le_bytes());
        }
        let c = read_pcd(&b).unwrap();
        assert_eq!(
            c.points,
            vec![Point3::new(1.0, 2.0, 3.0), Point3::new(-4.0, 5.5, 0.25)]
        );
        assert!(c.normals.is_none());
    }

    #[test]
    fn nan_normals_drop_all_normals() {
        let (pts, mut nrm) = sample(40);
        nrm[5] = Vector3::new(f64::NAN, 0.0, 0.0);
        let c = read_pcd(&write_pcd_binary(&pts, Some(&nrm))).unwrap();
        assert_eq!(c.len(), 40);
        assert!(c.normals.is_none());
    }

    fn msg(bytes: &[u8]) -> String {
        let e = read_pcd(bytes).unwrap_err();
        assert_eq!(e.field, "cloud.file");
        e.message
    }

    #[test]
    fn truncated_data() {
        let (pts, _) = sample(2000);
        let bin = write_pcd_binary(&pts, None);
        let m = msg(&bin[..bin.len() - 500 * 12]);
        assert!(
            m.contains("DATA section truncated: header says 2000 points, found 1500"),
            "{m}"
        );
        let m = msg(&bin[..bin.len() - 5]);
        assert!(m.contains("found 1999"), "{m}");
        let asc = write_pcd_ascii(&pts, None);
        let text = String::from_utf8(asc).unwrap();
        let cut: String = text.lines().take(11 + 1500).collect::<Vec<_>>().join("\n");
        let m = msg(cut.as_bytes());
        assert!(
            m.contains("DATA section truncated: header says 2000 points, found 1500"),
            "{m}"
        );
    }

    #[test]
    fn lying_counts_fail_without_allocating() {
        let (pts, _) = sample(10);
        for data in ["binary", "ascii"] {
            let bytes = if data == "binary" {
                write_pcd_binary(&pts, None)
            } else {
                write_pcd_ascii(&pts, None)
            };
            let text = String::from_utf8_lossy(&bytes).replace(
                "WIDTH 10\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 10",
                "WIDTH 1000000000000\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1000000000000",
            );
            let mut lying = text.as_bytes().to_vec();
            if data == "binary" {
                // Restore the binary body exactly (lossy conversion may have changed it).
                let body_at = bytes
                    .windows(12)
                    .position(|w| w == b"DATA binary\n")
                    .unwrap()
                    + 12;
                let hdr_end = lying
                    .windows(12)
                    .position(|w| w == b"DATA binary\n")
                    .unwrap()
                    + 12;
                lying.truncate(hdr_end);
                lying.extend_from_slice(&bytes[body_at..]);
            }
            let m = msg(&lying);
            assert!(
                m.contains("header says 1000000000000 points, found 10"),
                "{data}: {m}"
            );
        }
        // Counts that overflow.
        let m = msg(b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 18446744073709551615\nHEIGHT 3\nDATA binary\n");
        assert!(m.contains("overflows"), "{m}");
        let m = msg(b"FIELDS x y z w\nSIZE 4 4 4 8\nTYPE F F F F\nCOUNT 1 1 1 18446744073709551615\nPOINTS 1\nDATA binary\n");
        assert!(m.contains("overflows"), "{m}");
        let m = msg(b"FIELDS x y z w\nSIZE 4 4 4 8\nTYPE F F F F\nCOUNT 1 1 1 100000000000\nPOINTS 1\nDATA ascii\n1 2 3 4\n");
        assert!(m.contains("has 4 values, expected 100000000003"), "{m}");
        let m = msg(b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 5\nPOINTS 6\nDATA ascii\n");
        assert!(m.contains("POINTS 6 disagrees with WIDTH 5"), "{m}");
    }

    #[test]
    fn missing_and_bad_fields() {
        let m = msg(b"FIELDS x y\nSIZE 4 4\nTYPE F F\nPOINTS 1\nDATA ascii\n1 2\n");
        assert!(m.contains("FIELDS has no field z"), "{m}");
        let m = msg(b"FIELDS x y z\nSIZE 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n");
        assert!(
            m.contains("FIELDS lists 3 fields but SIZE gives 2 values"),
            "{m}"
        );
        let m = msg(b"FIELDS x y z\nSIZE 4 4 2\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n");
        assert!(m.contains("field z has TYPE F with SIZE 2"), "{m}");
        let m = msg(b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA binary_compressed\n");
        assert!(m.contains("binary_compressed is not supported"), "{m}");
        let m = msg(
            b"FIELDS x y z normal_x\nSIZE 4 4 4 4\nTYPE F F F F\nPOINTS 1\nDATA ascii\n1 2 3 4\n",
        );
        assert!(m.contains("only some normal components"), "{m}");
        let m = msg(b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 abc\n");
        assert!(
            m.contains("value \"abc\" of field z is not a number"),
            "{m}"
        );
        let m = msg(b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\n");
        assert!(m.contains("has no DATA line (the file ends first)"), "{m}");
        let m = msg(b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nBOGUS 1\nDATA ascii\n");
        assert!(m.contains("unknown keyword \"BOGUS\""), "{m}");
        let m = msg(b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nDATA ascii\n");
        assert!(m.contains("neither POINTS nor WIDTH"), "{m}");
        let m = msg(b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 3 1\nPOINTS 1\nDATA ascii\n");
        assert!(m.contains("field y has COUNT 3, expected 1"), "{m}");
    }

    #[test]
    fn garbage_and_huge_headers() {
        let m = msg(b"\x00\x01\x02\xff\xfe DATA");
        assert!(m.contains("PCD"), "{m}");
        let mut long = b"# ".to_vec();
        long.extend(std::iter::repeat_n(b'a', 100_000));
        let m = msg(&long);
        assert!(
            m.contains("no DATA line within the first 65536 bytes"),
            "{m}"
        );
        let mut bad = b"FIELDS x y z\nSIZE 4 4 4\n".to_vec();
        bad.extend_from_slice(&[0xff, 0xfe, b'\n']);
        let m = msg(&bad);
        assert!(m.contains("header line 3 is not text"), "{m}");
    }
}
