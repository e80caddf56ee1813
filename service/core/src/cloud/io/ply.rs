//! PLY (Stanford polygon) files: `ascii`, `binary_little_endian` and `binary_big_endian`.
//! Only the `vertex` element is read (x, y, z and, when present, nx/ny/nz or
//! normal_x/normal_y/normal_z); elements before it are skipped, elements after it (faces) are
//! not looked at. See the module docs of [`super`] for why this is hand-written.

use super::{
    CloudBuilder, Slot, Tokens, bounded_capacity, check_writer_normals, error, normals_present,
    parse_number, show, split_header,
};
use crate::cloud::PointCloud;
use crate::error::FieldError;
use nalgebra::{Point3, Vector3};
use std::fmt::Write as _;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn of(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// Reads one value from the start of `b` (`None` if `b` is too short).
    fn read(self, b: &[u8], big: bool) -> Option<f64> {
        macro_rules! rd {
            ($t:ty) => {{
                let a = b.get(..std::mem::size_of::<$t>())?.try_into().ok()?;
                (if big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }) as f64
            }};
        }
        Some(match self {
            Scalar::I8 => rd!(i8),
            Scalar::U8 => rd!(u8),
            Scalar::I16 => rd!(i16),
            Scalar::U16 => rd!(u16),
            Scalar::I32 => rd!(i32),
            Scalar::U32 => rd!(u32),
            Scalar::F32 => rd!(f32),
            Scalar::F64 => rd!(f64),
        })
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
}

impl Element {
    /// Fewest bytes one element takes in a binary body (a list takes at least its count).
    fn min_binary_size(&self) -> usize {
        self.props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => s.size(),
                Kind::List { count, .. } => count.size(),
            })
            .sum()
    }

    fn all_scalar(&self) -> bool {
        self.props.iter().all(|p| matches!(p.kind, Kind::Scalar(_)))
    }

    /// "2000 vertices" / "12 'face' elements", for messages.
    fn describe(&self, n: u64) -> String {
        if self.name == "vertex" {
            format!("{n} vertices")
        } else {
            format!("{n} '{}' elements", self.name)
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Ascii,
    Binary { big: bool },
}

#[derive(Debug)]
struct Header {
    format: Format,
    elements: Vec<Element>,
    body_start: usize,
    lines: usize,
}

fn parse_header(bytes: &[u8]) -> Result<Header, FieldError> {
    if !(bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n")) {
        return Err(error("PLY: the file does not start with the line \"ply\""));
    }
    let (lines, body_start) =
        split_header(bytes, "PLY", "end_header", |l| l.trim() == "end_header")?;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for (no, text) in lines.iter().skip(1) {
        let no = *no;
        let words: Vec<&str> = text.split_ascii_whitespace().collect();
        let bad = |what: &str| {
            error(format!(
                "PLY: header line {no}: {what}: \"{}\"",
                show(text.as_bytes())
            ))
        };
        match words.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] | ["end_header"] => {}
            ["format", f, _version] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Binary { big: false },
                    "binary_big_endian" => Format::Binary { big: true },
                    _ => return Err(bad("unknown format")),
                })
            }
            ["element", name, count] => {
                let count = count
                    .parse::<u64>()
                    .map_err(|_| bad("element count is not a non-negative integer"))?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            ["property", "list", c, i, name] => {
                let count = Scalar::of(c)
                    .filter(|s| s.is_integer())
                    .ok_or_else(|| bad("list count type must be an integer type"))?;
                let item = Scalar::of(i).ok_or_else(|| bad("unknown list item type"))?;
                let e = elements
                    .last_mut()
                    .ok_or_else(|| bad("property before any element"))?;
                e.props.push(Property {
                    name: name.to_string(),
                    kind: Kind::List { count, item },
                });
            }
            ["property", ty, name] => {
                let s = Scalar::of(ty).ok_or_else(|| bad("unknown property type"))?;
                let e = elements
                    .last_mut()
                    .ok_or_else(|| bad("property before any element"))?;
                e.props.push(Property {
                    name: name.to_string(),
                    kind: Kind::Scalar(s),
                });
            }
            _ => return Err(bad("not a PLY header line")),
        }
    }
    let format = format.ok_or_else(|| error("PLY: the header has no format line"))?;
    Ok(Header {
        format,
        elements,
        body_start,
        lines: lines.len(),
    })
}

/// Reads a PLY file (ascii, binary little- or big-endian): the vertex element's x, y, z and,
/// when present, normals. Never panics; errors name what is wrong.
pub fn read_ply(bytes: &[u8]) -> Result<PointCloud, FieldError> {
    let header = parse_header(bytes)?;
    let vi = header
        .elements
        .iter()
        .position(|e| e.name == "vertex")
        .ok_or_else(|| error("PLY: the header has no vertex element"))?;
    let vertex = &header.elements[vi];
    // Slot of each vertex property (first occurrence of a name wins).
    let mut prop_slot: Vec<Option<usize>> = vec![None; vertex.props.len()];
    let mut slot_name: [Option<String>; 6] = Default::default();
    for (k, p) in vertex.props.iter().enumerate() {
        if let Some(s) = Slot::of(&p.name)
            && slot_name[s.index()].is_none()
        {
            if matches!(p.kind, Kind::List { .. }) {
                return Err(error(format!(
                    "PLY: vertex property {} is a list, expected a scalar",
                    p.name
                )));
            }
            prop_slot[k] = Some(s.index());
            slot_name[s.index()] = Some(p.name.clone());
        }
    }
    for (s, axis) in [(Slot::X, "x"), (Slot::Y, "y"), (Slot::Z, "z")] {
        if slot_name[s.index()].is_none() {
            return Err(error(format!("PLY: vertex element has no property {axis}")));
        }
    }
    let with_normals = normals_present("PLY", &slot_name)?;
    let body = bytes.get(header.body_start..).unwrap_or(&[]);
    match header.format {
        Format::Binary { big } => {
            let mut cur = Cursor { b: body, pos: 0 };
            for e in &header.elements[..vi] {
                skip_binary(&mut cur, e, big)?;
            }
            read_vertices_binary(&mut cur, vertex, &prop_slot, with_normals, big)
        }
        Format::Ascii => {
            let mut tok = Tokens::new(body, header.lines + 1);
            for e in &header.elements[..vi] {
                skip_ascii(&mut tok, e)?;
            }
            read_vertices_ascii(&mut tok, vertex, &prop_slot, with_normals)
        }
    }
}

struct Cursor<'a> {
    b: &'a [u8],
    pos: usize,
}

impl<'a> Cursor<'a> {
    fn remaining(&self) -> usize {
        self.b.len().saturating_sub(self.pos)
    }

    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.pos.checked_add(n)?;
        let s = self.b.get(self.pos..end)?;
        self.pos = end;
        Some(s)
    }
}

fn truncated(e: &Element, found: u64) -> FieldError {
    error(format!(
        "PLY: data truncated: header says {}, found {found}",
        e.describe(e.count)
    ))
}

/// Fails fast when even the smallest records cannot fit; returns how many can.
fn check_room(cur: &Cursor, e: &Element) -> Result<usize, FieldError> {
    let min = e.min_binary_size().max(1);
    let room = cur.remaining() / min;
    if e.count > room as u64 {
        return Err(if e.all_scalar() {
            truncated(e, room as u64)
        } else {
            error(format!(
                "PLY: data truncated: header says {}, of at least {min} bytes each, but only {} \
                 bytes remain",
                e.describe(e.count),
                cur.remaining()
            ))
        });
    }
    Ok(room)
}

fn list_len(v: f64, e: &Element, p: &Property) -> Result<usize, FieldError> {
    if v < 0.0 {
        return Err(error(format!(
            "PLY: element {} property {}: negative list length {v}",
            e.name, p.name
        )));
    }
    Ok(v as usize)
}

fn skip_binary(cur: &mut Cursor, e: &Element, big: bool) -> Result<(), FieldError> {
    if e.props.is_empty() || e.count == 0 {
        return Ok(());
    }
    check_room(cur, e)?;
    if e.all_scalar() {
        // count * size <= remaining by check_room.
        let n = e.count as usize * e.min_binary_size();
        cur.take(n).ok_or_else(|| truncated(e, 0))?;
        return Ok(());
    }
    for i in 0..e.count {
        for p in &e.props {
            let ok = match p.kind {
                Kind::Scalar(s) => cur.take(s.size()).is_some(),
                Kind::List { count, item } => {
                    let Some(n) = cur.take(count.size()).and_then(|b| count.read(b, big)) else {
                        return Err(truncated(e, i));
                    };
                    let n = list_len(n, e, p)?;
                    n.checked_mul(item.size())
                        .and_then(|bytes| cur.take(bytes))
                        .is_some()
                }
            };
            if !ok {
                return Err(truncated(e, i));
            }
        }
    }
    Ok(())
}

fn read_vertices_binary(
    cur: &mut Cursor,
    e: &Element,
    prop_slot: &[Option<usize>],
    with_normals: bool,
    big: bool,
) -> Result<PointCloud, FieldError> {
    let room = check_room(cur, e)?;
    let mut out = CloudBuilder::new(bounded_capacity(e.count, room), with_normals);
    for i in 0..e.count {
        let mut v = [0.0f64; 6];
        for (p, slot) in e.props.iter().zip(prop_slot) {
            match p.kind {
                Kind::Scalar(s) => {
                    let x = cur
                        .take(s.size())
                        .and_then(|b| s.read(b, big))
                        .ok_or_else(|| truncated(e, i))?;
                    if let Some(k) = slot {
                        v[*k] = x;
                    }
                }
                Kind::List { count, item } => {
                    let n = cur
                        .take(count.size())
                        .and_then(|b| count.read(b, big))
                        .ok_or_else(|| truncated(e, i))?;
                    let n = list_len(n, e, p)?;
                    n.checked_mul(item.size())
                        .and_then(|bytes| cur.take(bytes))
                        .ok_or_else(|| truncated(e, i))?;
                }
            }
        }
        out.push(&v);
    }
    Ok(out.finish())
}

fn skip_ascii(tok: &mut Tokens, e: &Element) -> Result<(), FieldError> {
    if e.props.is_empty() {
        return Ok(());
    }
    // Each element takes at least one token, so this loop ends with the input.
    for i in 0..e.count {
        for p in &e.props {
            let t = tok.next_token().ok_or_else(|| truncated(e, i))?;
            if let Kind::List { .. } = p.kind {
                let n = ascii_list_len(t, e, p, tok.line)?;
                for _ in 0..n {
                    tok.next_token().ok_or_else(|| truncated(e, i))?;
                }
            }
        }
    }
    Ok(())
}

fn ascii_list_len(t: &[u8], e: &Element, p: &Property, line: usize) -> Result<u64, FieldError> {
    std::str::from_utf8(t)
        .ok()
        .and_then(|s| s.parse::<u64>().ok())
        .ok_or_else(|| {
            error(format!(
                "PLY: line {line}: list length \"{}\" of {} property {} is not a non-negative \
                 integer",
                show(t),
                e.name,
                p.name
            ))
        })
}

fn read_vertices_ascii(
    tok: &mut Tokens,
    e: &Element,
    prop_slot: &[Option<usize>],
    with_normals: bool,
) -> Result<PointCloud, FieldError> {
    // Every vertex takes at least two bytes per property ("1 2 3\n").
    let room = tok.remaining() / (2 * e.props.len().max(1));
    let mut out = CloudBuilder::new(bounded_capacity(e.count, room), with_normals);
    for i in 0..e.count {
        let mut v = [0.0f64; 6];
        for (p, slot) in e.props.iter().zip(prop_slot) {
            let t = tok.next_token().ok_or_else(|| truncated(e, i))?;
            match p.kind {
                Kind::Scalar(_) => {
                    if let Some(k) = slot {
                        v[*k] = parse_number(t).ok_or_else(|| {
                            error(format!(
                                "PLY: vertex {i} (line {}): value \"{}\" of property {} is not a \
                                 number",
                                tok.line,
                                show(t),
                                p.name
                            ))
                        })?;
                    }
                }
                Kind::List { .. } => {
                    let n = ascii_list_len(t, e, p, tok.line)?;
                    for _ in 0..n {
                        tok.next_token().ok_or_else(|| truncated(e, i))?;
                    }
                }
            }
        }
        out.push(&v);
    }
    Ok(out.finish())
}

fn header_text(n: usize, with_normals: bool, format: &str) -> String {
    let mut s = format!(
        "ply\nformat {format} 1.0\ncomment graspd\nelement vertex {n}\nproperty float x\n\
         property float y\nproperty float z\n"
    );
    if with_normals {
        s.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    s.push_str("end_header\n");
    s
}

/// Writes a binary little-endian PLY: float32 x y z (plus nx ny nz when given), no faces.
///
/// # Panics
/// If `normals` is given with a length other than `points.len()` (a caller bug).
pub fn write_ply_binary(points: &[Point3<f64>], normals: Option<&[Vector3<f64>]>) -> Vec<u8> {
    check_writer_normals(points, normals);
    let mut out = header_text(points.len(), normals.is_some(), "binary_little_endian").into_bytes();
    out.reserve(points.len() * if normals.is_some() { 24 } else { 12 });
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

/// Writes an ascii PLY: float32 x y z (plus nx ny nz when given), no faces.
///
/// # Panics
/// If `normals` is given with a length other than `points.len()` (a caller bug).
pub fn write_ply_ascii(points: &[Point3<f64>], normals: Option<&[Vector3<f64>]>) -> Vec<u8> {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(n: usize) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
        let pts = (0..n)
            .map(|i| {
                let t = i as f64 * 0.41;
                Point3::new(t.cos() * 0.03, t.sin() * 0.03 - 0.2, 0.5 - i as f64 * 1e-4)
            })
            .collect();
        let nrm = (0..n)
            .map(|i| {
                let t = i as f64 * 0.41;
                Vector3::new(t.cos(), t.sin(), 0.0)
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

    fn msg(bytes: &[u8]) -> String {
        let e = read_ply(bytes).unwrap_err();
        assert_eq!(e.field, "cloud.file");
        e.message
    }

    #[test]
    fn round_trips() {
        let (pts, nrm) = sample(250);
        for bytes in [write_ply_ascii(&pts, None), write_ply_binary(&pts, None)] {
            let c = read_ply(&bytes).unwrap();
            close(&c.points, &pts);
            assert!(c.normals.is_none());
        }
        for bytes in [
            write_ply_ascii(&pts, Some(&nrm)),
            write_ply_binary(&pts, Some(&nrm)),
        ] {
            let c = read_ply(&bytes).unwrap();
            close(&c.points, &pts);
            for (a, b) in c.normals.unwrap().iter().zip(&nrm) {
                assert!((a - b).norm() < 1e-6);
            }
        }
        assert!(read_ply(&write_ply_binary(&[], None)).unwrap().is_empty());
    }

    #[test]
    fn hand_written_ascii_with_faces_and_crlf() {
        let text = "ply\r\n\
            format ascii 1.0\r\n\
            comment made by hand\r\n\
            obj_info nothing\r\n\
            element vertex 3\r\n\
            property float x\r\n\
            property float y\r\n\
            property float z\r\n\
            property uchar red\r\n\
            property float nx\r\n\
            property float ny\r\n\
            property float nz\r\n\
            element face 1\r\n\
            property list uchar int vertex_indices\r\n\
            end_header\r\n\
            0.5 -0.25 1e-3 255 0 0 1\r\n\
            1 2 3 0 1 0 0\r\n\
            -1 -2 -3.5 7 0 -1 0\r\n\
            3 0 1 2\r\n";
        let c = read_ply(text.as_bytes()).unwrap();
        assert_eq!(
            c.points,
            vec![
                Point3::new(0.5, -0.25, 0.001),
                Point3::new(1.0, 2.0, 3.0),
                Point3::new(-1.0, -2.0, -3.5)
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
    fn binary_big_endian_doubles_after_another_element() {
        // A 'camera' element with a list comes before the vertices.
        let mut b = b"ply\nformat binary_big_endian 1.0\nelement camera 2\nproperty list uchar float k\nproperty short id\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\nproperty list uchar int junk\nend_header\n".to_vec();
        for id in 0..2i16 {
            b.push(2);
            b.extend_from_slice(&1.5f32.to_be_bytes());
            b.extend_from_slice(&2.5f32.to_be_bytes());
            b.extend_from_slice(&id.to_be_bytes());
        }
        for (x, y, z) in [(1.0f64, 2.0f64, 3.0f64), (0.125, -7.0, 1e-3)] {
            for v in [x, y, z] {
                b.extend_from_slice(&v.to_be_bytes());
            }
            b.push(1);
            b.extend_from_slice(&42i32.to_be_bytes());
        }
        let c = read_ply(&b).unwrap();
        assert_eq!(
            c.points,
            vec![Point3::new(1.0, 2.0, 3.0), Point3::new(0.125, -7.0, 1e-3)]
        );
    }

    #[test]
    fn truncated_data() {
        let (pts, _) = sample(2000);
        let bin = write_ply_binary(&pts, None);
        let m = msg(&bin[..bin.len() - 500 * 12]);
        assert!(
            m.contains("data truncated: header says 2000 vertices, found 1500"),
            "{m}"
        );
        let asc = String::from_utf8(write_ply_ascii(&pts, None)).unwrap();
        let cut: String = asc.lines().take(8 + 1500).collect::<Vec<_>>().join("\n");
        let m = msg(cut.as_bytes());
        assert!(
            m.contains("data truncated: header says 2000 vertices, found 1500"),
            "{m}"
        );
    }

    #[test]
    fn lying_counts_fail_cleanly() {
        let (pts, _) = sample(10);
        for bytes in [write_ply_binary(&pts, None), write_ply_ascii(&pts, None)] {
            let at = bytes
                .windows(15)
                .position(|w| w == b"element vertex ")
                .unwrap()
                + 15;
            let mut lying = bytes[..at].to_vec();
            lying.extend_from_slice(b"1000000000000");
            lying.extend_from_slice(&bytes[at + 2..]);
            let m = msg(&lying);
            assert!(
                m.contains("header says 1000000000000 vertices, found 10"),
                "{m}"
            );
        }
        // A property-less element with a huge count before the vertices costs nothing.
        let ok = b"ply\nformat binary_little_endian 1.0\nelement nothing 18446744073709551615\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\x80?\0\0\0@\0\0@@";
        let c = read_ply(ok).unwrap();
        assert_eq!(c.points, vec![Point3::new(1.0, 2.0, 3.0)]);
        let ok_ascii = b"ply\nformat ascii 1.0\nelement nothing 18446744073709551615\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n";
        assert_eq!(read_ply(ok_ascii).unwrap().len(), 1);
        // A list claiming 4e9 items.
        let mut b = b"ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uint int idx\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec();
        b.extend_from_slice(&u32::MAX.to_le_bytes());
        b.extend_from_slice(&[0; 12]);
        let m = msg(&b);
        assert!(m.contains("header says 1 'face' elements, found 0"), "{m}");
        let m = msg(b"ply\nformat ascii 1.0\nelement face 1\nproperty list uint int idx\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n4000000000 1 2 3\n");
        assert!(m.contains("'face' elements, found 0"), "{m}");
        let m = msg(b"ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\nproperty float x\nend_header\n");
        assert!(
            m.contains("element count is not a non-negative integer"),
            "{m}"
        );
    }

    #[test]
    fn missing_and_bad_properties() {
        let m = msg(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n");
        assert!(m.contains("vertex element has no property z"), "{m}");
        let m = msg(b"ply\nformat ascii 1.0\nelement face 0\nend_header\n");
        assert!(m.contains("no vertex element"), "{m}");
        let m = msg(b"ply\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n");
        assert!(m.contains("no format line"), "{m}");
        let m = msg(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nend_header\n1 2 3 4\n");
        assert!(
            m.contains("only some normal components are present (nx)"),
            "{m}"
        );
        let m = msg(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty list uchar float z\nend_header\n1 2 1 3\n");
        assert!(m.contains("vertex property z is a list"), "{m}");
        let m = msg(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 zz\n");
        assert!(
            m.contains("value \"zz\" of property z is not a number"),
            "{m}"
        );
        let m = msg(b"ply\nformat binary_middle_endian 1.0\nend_header\n");
        assert!(m.contains("unknown format"), "{m}");
        let m = msg(b"ply\nformat ascii 1.0\nproperty float x\nend_header\n");
        assert!(m.contains("property before any element"), "{m}");
        let m = msg(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n");
        assert!(m.contains("unknown property type"), "{m}");
        let m = msg(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
        assert!(m.contains("has no end_header line"), "{m}");
        let m = msg(b"PLY\nformat ascii 1.0\n");
        assert!(m.contains("does not start with"), "{m}");
    }

    #[test]
    fn garbage_after_the_magic() {
        let mut b = b"ply\n".to_vec();
        b.extend((0..=255u8).cycle().take(5000));
        let m = msg(&b);
        assert!(m.starts_with("PLY: "), "{m}");
    }
}
