//! Binary MSH files, 2.2 and 4.1 (`size_t` of 8 or 4 bytes), little or big endian: values and
//! the text lines between them, each error naming its byte offset.

use std::io::{self, BufRead};
use std::path::Path;

use glam::DVec3;

use std::collections::HashMap;

use super::ascii::{PhysicalName, add_physical_name};
use super::model::{Elements, Nodes};
use super::source::element_dim;
use super::{TETRAHEDRON, TRIANGLE, is_section};
use crate::io::{IoError, bounded_vec, read_error, shown};

/// Number of nodes of each Gmsh element type (`None`: no such type, or one of variable size), as
/// Gmsh 4.8's `getElementProperties` gives them (prisms 90, 91 and 106–117 and type 140, which it
/// lacks, by their names in `GmshDefines.h`: `MSH_PRI_40` has 40 nodes, …). Binary files need
/// it to step over the elements of the types not read.
fn nodes_per_element(kind: i32) -> Option<u64> {
    Some(match kind {
        15 | 84..=89 | 132 => 1,
        1 => 2,
        2 | 8 => 3,
        3 | 4 | 26 | 140 => 4,
        7 | 27 => 5,
        6 | 9 | 28 => 6,
        62 => 7,
        5 | 16 | 63 => 8,
        10 | 20 | 64 => 9,
        11 | 21 | 65 => 10,
        66 => 11,
        22 | 39 => 12,
        19 => 13,
        14 => 14,
        18 | 23 | 24 => 15,
        36 | 40 | 137 => 16,
        13 | 52 => 18,
        17 | 29 | 41 => 20,
        25 | 53 | 125 => 21,
        32 => 22,
        54 | 57 | 111 => 24,
        37 => 25,
        12 | 55 => 27,
        33 | 42 | 58 => 28,
        126 => 29,
        56 | 118 => 30,
        59 | 99 => 32,
        112 => 33,
        79 => 34,
        30 => 35,
        38 | 43 | 60 => 36,
        127 => 37,
        61 | 80 | 90 => 40,
        113 => 42,
        100 => 44,
        44 | 128 => 45,
        81 => 46,
        47 => 49,
        114 => 51,
        82 => 52,
        129 => 53,
        45 | 119 => 55,
        31 | 101 => 56,
        83 => 58,
        115 => 60,
        130 => 61,
        48 | 92 => 64,
        46 => 66,
        102 => 68,
        116 | 131 => 69,
        91 => 75,
        117 => 78,
        103 => 80,
        49 => 81,
        71 => 84,
        120 => 91,
        104 => 92,
        50 => 100,
        105 => 104,
        72 => 120,
        51 => 121,
        93 => 125,
        106 => 126,
        121 => 140,
        73 => 165,
        107 => 196,
        122 => 204,
        94 => 216,
        74 => 220,
        123 => 285,
        75 => 286,
        108 => 288,
        95 => 343,
        124 => 385,
        109 => 405,
        96 => 512,
        110 => 550,
        97 => 729,
        98 => 1000,
        _ => return None,
    })
}

/// Most bytes of a text line kept in a binary file (section keywords, counts): a longer line is
/// no keyword, and binary data without line breaks must not pile up in memory.
const LINE_KEPT: usize = 256;

/// A binary `.msh` file after its version line: binary values, text lines between them, and the
/// byte offset of each for errors.
pub(super) struct Binary<'p, R> {
    pub(super) reader: R,
    pub(super) offset: u64,
    pub(super) path: &'p Path,
    pub(super) big_endian: bool,
    /// Bytes of a `size_t` (4.1: 8 or 4, as the version line says).
    pub(super) size_t: usize,
}

impl<R: BufRead> Binary<'_, R> {
    fn error(&self, offset: u64, message: impl Into<String>) -> IoError {
        IoError::Binary { path: self.path.to_path_buf(), offset, message: message.into() }
    }

    /// The next `N` bytes, in little-endian order; at the end of the file, an error that the
    /// file ends inside `what()`.
    fn bytes<const N: usize>(&mut self, what: &dyn Fn() -> String) -> Result<[u8; N], IoError> {
        let mut buf = [0; N];
        match self.reader.read_exact(&mut buf) {
            Ok(()) => {}
            Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => {
                return Err(self.error(self.offset, format!("file ends inside {}", what())));
            }
            Err(e) => return Err(read_error(self.path, e)),
        }
        self.offset += N as u64;
        if self.big_endian {
            buf.reverse();
        }
        Ok(buf)
    }

    /// An `int` (4 bytes).
    fn int(&mut self, what: &dyn Fn() -> String) -> Result<i32, IoError> {
        self.bytes::<4>(what).map(i32::from_le_bytes)
    }

    /// A `size_t` (8 or 4 bytes).
    fn size(&mut self, what: &dyn Fn() -> String) -> Result<u64, IoError> {
        if self.size_t == 4 {
            self.bytes::<4>(what).map(|b| u32::from_le_bytes(b).into())
        } else {
            self.bytes::<8>(what).map(u64::from_le_bytes)
        }
    }

    /// A `double`.
    fn double(&mut self, what: &dyn Fn() -> String) -> Result<f64, IoError> {
        self.bytes::<8>(what).map(f64::from_le_bytes)
    }

    /// Steps over `count` values of `size` bytes each, as [`Self::bytes`] would read them.
    fn skip(&mut self, count: u64, size: u64, what: &dyn Fn() -> String) -> Result<(), IoError> {
        let start = self.offset;
        let Some(mut left) = count.checked_mul(size) else {
            return Err(self.error(start, format!("{} claims more bytes than a file can hold", what())));
        };
        while left > 0 {
            let available = match self.reader.fill_buf() {
                Ok(buf) => buf.len(),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(read_error(self.path, e)),
            };
            if available == 0 {
                return Err(self.error(start, format!("file ends inside {}", what())));
            }
            let step = available.min(usize::try_from(left).unwrap_or(usize::MAX));
            self.reader.consume(step);
            self.offset += step as u64;
            left -= step as u64;
        }
        Ok(())
    }

    /// The next line (through its `\n`), trimmed, at most [`LINE_KEPT`] bytes of it kept, and
    /// its offset; `None` at the end of the file.
    fn raw_line(&mut self) -> Result<Option<(u64, String)>, IoError> {
        let start = self.offset;
        let mut kept = Vec::new();
        let mut any = false;
        loop {
            let (step, done) = {
                let buf = match self.reader.fill_buf() {
                    Ok(buf) => buf,
                    Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                    Err(e) => return Err(read_error(self.path, e)),
                };
                if buf.is_empty() {
                    break;
                }
                let (step, done) = match buf.iter().position(|&c| c == b'\n') {
                    Some(i) => (i + 1, true),
                    None => (buf.len(), false),
                };
                let room = LINE_KEPT.saturating_sub(kept.len()).min(step);
                kept.extend_from_slice(&buf[..room]);
                (step, done)
            };
            any = true;
            self.reader.consume(step);
            self.offset += step as u64;
            if done {
                break;
            }
        }
        Ok(any.then(|| (start, String::from_utf8_lossy(kept.trim_ascii()).into_owned())))
    }

    /// The next non-blank line, as [`Self::raw_line`].
    fn line(&mut self) -> Result<Option<(u64, String)>, IoError> {
        while let Some((offset, text)) = self.raw_line()? {
            if !text.is_empty() {
                return Ok(Some((offset, text)));
            }
        }
        Ok(None)
    }

    /// The next non-blank line, which must be `keyword`; `context` is added to errors.
    fn expect_line(&mut self, keyword: &str, context: &str) -> Result<(), IoError> {
        match self.line()? {
            Some((_, text)) if text == keyword => Ok(()),
            Some((offset, text)) => {
                Err(self.error(offset, format!("expected '{keyword}'{context}, found '{}'", shown(&text))))
            }
            None => Err(self.error(self.offset, format!("file ends early: expected '{keyword}'{context}"))),
        }
    }

    /// The next non-blank line as one non-negative integer (a count in MSH 2.2).
    fn count_line(&mut self, what: &str) -> Result<u64, IoError> {
        match self.line()? {
            Some((offset, text)) => {
                text.parse().map_err(|_| self.error(offset, format!("expected {what}, found '{}'", shown(&text))))
            }
            None => Err(self.error(self.offset, format!("file ends early: expected {what}"))),
        }
    }
}

/// The sections of a binary file after its version line.
pub(super) fn read_binary<R: BufRead>(
    b: &mut Binary<'_, R>,
    version_2: bool,
) -> Result<(Nodes, Elements, Vec<PhysicalName>), IoError> {
    let mark = b.offset;
    let one = b.bytes::<4>(&|| "the integer 1 that gives a binary file's byte order".to_owned())?;
    b.big_endian = match one {
        [1, 0, 0, 0] => false,
        [0, 0, 0, 1] => true,
        _ => {
            return Err(b.error(
                mark,
                format!("expected the integer 1 in little or big endian (the byte order mark), found bytes {one:02X?}"),
            ));
        }
    };
    b.expect_line("$EndMeshFormat", "")?;

    let mut nodes = Nodes::default();
    let mut elements = Elements::default();
    let mut names = Vec::new();
    let mut entities = HashMap::new();
    while let Some((offset, section)) = b.line()? {
        match section.as_str() {
            "$Nodes" if version_2 => read_nodes_2_binary(b, &mut nodes, offset)?,
            "$Nodes" => read_nodes_41_binary(b, &mut nodes, offset)?,
            "$Elements" if version_2 => read_elements_2_binary(b, &nodes, &mut elements, offset)?,
            "$Elements" => read_elements_41_binary(b, &nodes, &mut elements, offset, &entities)?,
            "$Entities" if !version_2 => entities = read_entities_binary(b, offset)?,
            "$PhysicalNames" => read_physical_names_binary(b, offset, &mut names)?,
            s if is_section(s) => {
                // Found by its line: Gmsh ends every section's binary data with a line break.
                let end = format!("$End{}", &s[1..]);
                loop {
                    match b.raw_line()? {
                        Some((_, text)) if text == end => break,
                        Some(_) => {}
                        None => {
                            return Err(b.error(
                                b.offset,
                                format!("file ends early: expected '{end}' (closing '{s}' at byte offset {offset})"),
                            ));
                        }
                    }
                }
            }
            s => return Err(b.error(offset, format!("expected a section such as '$Nodes', found '{}'", shown(s)))),
        }
    }
    Ok((nodes, elements, names))
}

/// `$PhysicalNames` of a binary file: text lines, as in an ASCII file, added to `names`.
fn read_physical_names_binary<R: BufRead>(
    b: &mut Binary<'_, R>,
    at: u64,
    names: &mut Vec<PhysicalName>,
) -> Result<(), IoError> {
    let count = b.count_line("the number of physical names")?;
    for i in 1..=count {
        let Some((offset, text)) = b.line()? else {
            let what = format!("physical name {i} of {count} ($PhysicalNames at byte offset {at})");
            return Err(b.error(b.offset, format!("file ends early: expected {what}")));
        };
        add_physical_name(names, &text).map_err(|m| b.error(offset, m))?;
    }
    b.expect_line("$EndPhysicalNames", &format!(" (closing '$PhysicalNames' at byte offset {at})"))
}

/// Binary MSH 4.1 `$Entities`: four counts, then points (`int` tag, 3 `double`s, physical tags)
/// and curves, surfaces and volumes (`int` tag, 6 `double`s, physical tags, bounding entities),
/// each list a `size_t` count of `int`s. Returns the physical tags of each (dimension, tag).
fn read_entities_binary<R: BufRead>(b: &mut Binary<'_, R>, at: u64) -> Result<HashMap<(i32, i64), Vec<i64>>, IoError> {
    let header = || format!("the counts of $Entities (at byte offset {at})");
    let counts = [b.size(&header)?, b.size(&header)?, b.size(&header)?, b.size(&header)?];
    let mut entities = HashMap::new();
    for (dim, (&count, kind)) in counts.iter().zip(["point", "curve", "surface", "volume"]).enumerate() {
        for i in 0..count {
            let what = || format!("{kind} entity {} of {count} ($Entities at byte offset {at})", i + 1);
            let tag = b.int(&what)?;
            b.skip(if dim == 0 { 3 } else { 6 }, 8, &what)?;
            let n = b.size(&what)?;
            let mut physical = bounded_vec(usize::try_from(n).unwrap_or(usize::MAX));
            for _ in 0..n {
                physical.push(i64::from(b.int(&what)?));
            }
            entities.insert((dim as i32, i64::from(tag)), physical);
            if dim > 0 {
                let n = b.size(&what)?;
                b.skip(n, 4, &what)?;
            }
        }
    }
    b.expect_line("$EndEntities", &format!(" (closing '$Entities' at byte offset {at})"))?;
    Ok(entities)
}

/// Binary MSH 4.1 `$Nodes`: the `size_t`s `blocks nodes min max`, then per block the `int`s
/// `dim entity parametric` and a `size_t` count, the blocks' `size_t` tags, then per node x y z
/// and, if parametric, `dim` more `double`s (stepped over).
fn read_nodes_41_binary<R: BufRead>(b: &mut Binary<'_, R>, nodes: &mut Nodes, at: u64) -> Result<(), IoError> {
    let header =
        || format!("the header of $Nodes (at byte offset {at}): 'numEntityBlocks numNodes minNodeTag maxNodeTag'");
    let [blocks, count, _, _] = [b.size(&header)?, b.size(&header)?, b.size(&header)?, b.size(&header)?];
    nodes.reserve(count);
    let mut total = 0u64;
    for block in 1..=blocks {
        let start = b.offset;
        let what = || format!("node block {block} of {blocks} ($Nodes at byte offset {at})");
        let [dim, _, parametric] = [b.int(&what)?, b.int(&what)?, b.int(&what)?];
        let n = b.size(&what)?;
        let extra = match (parametric, dim) {
            (0, _) => 0,
            (1, 0..=3) => dim.unsigned_abs().into(),
            (1, _) => return Err(b.error(start, format!("node block {block}: entity dimension {dim} is not 0 to 3"))),
            _ => {
                return Err(
                    b.error(start + 8, format!("node block {block}: parametric flag {parametric} is not 0 or 1"))
                );
            }
        };
        let mut tags = bounded_vec(usize::try_from(n).unwrap_or(usize::MAX));
        for k in 0..n {
            let offset = b.offset;
            let tag = b.size(&|| format!("tag {} of {n} of node block {block}", k + 1))?;
            nodes.add(tag, k).map_err(|e| b.error(offset, e.to_string()))?;
            tags.push(tag);
        }
        for (k, tag) in tags.iter().enumerate() {
            let what = || format!("the coordinates of node {tag} ({} of {n} of node block {block})", k + 1);
            nodes.origins.push(b.offset);
            let p = DVec3::new(b.double(&what)?, b.double(&what)?, b.double(&what)?);
            b.skip(extra, 8, &what)?;
            nodes.positions.push(p);
        }
        total = total.saturating_add(n);
    }
    let end = b.offset;
    b.expect_line("$EndNodes", &format!(" (closing '$Nodes' at byte offset {at}, which has {blocks} blocks)"))?;
    if total != count {
        return Err(b.error(end, format!("$Nodes at byte offset {at} says {count} nodes, but its blocks hold {total}")));
    }
    Ok(())
}

/// Binary MSH 4.1 `$Elements`: the `size_t`s `blocks elements min max`, then per block the
/// `int`s `dim entity type` and a `size_t` count, then per element its `size_t` tag and node tags.
fn read_elements_41_binary<R: BufRead>(
    b: &mut Binary<'_, R>,
    nodes: &Nodes,
    out: &mut Elements,
    at: u64,
    entities: &HashMap<(i32, i64), Vec<i64>>,
) -> Result<(), IoError> {
    let header = || {
        format!(
            "the header of $Elements (at byte offset {at}): 'numEntityBlocks numElements minElementTag maxElementTag'"
        )
    };
    let [blocks, count, _, _] = [b.size(&header)?, b.size(&header)?, b.size(&header)?, b.size(&header)?];
    let size = b.size_t as u64;
    let mut total = 0u64;
    for block in 1..=blocks {
        let start = b.offset;
        let what = || format!("element block {block} of {blocks} ($Elements at byte offset {at})");
        let [dim, entity, kind] = [b.int(&what)?, b.int(&what)?, b.int(&what)?];
        let n = b.size(&what)?;
        let groups = entities.get(&(dim, i64::from(entity))).map_or(&[][..], Vec::as_slice);
        let corners = nodes_per_element(kind).ok_or_else(|| {
            b.error(
                start + 8,
                format!("element block {block}: element type {kind} is not a Gmsh element type of fixed size"),
            )
        })?;
        let kind = usize::try_from(kind).unwrap_or(0);
        if kind == TETRAHEDRON || kind == TRIANGLE {
            for k in 1..=n {
                let offset = b.offset;
                let what = || format!("element {k} of {n} of element block {block} (type {kind})");
                let id = b.size(&what)?;
                let mut v = [0u32; 4];
                for slot in v.iter_mut().take(usize::try_from(corners).unwrap_or(0)) {
                    let tag = b.size(&what)?;
                    *slot = nodes.index.get(&tag).copied().ok_or_else(|| {
                        b.error(offset, format!("element {id}: node tag {tag} is not defined in $Nodes"))
                    })?;
                }
                out.add_to_groups(dim, groups, &v[..usize::try_from(corners).unwrap_or(0).min(4)]);
                out.push(kind, id, v, offset);
            }
        } else if !groups.is_empty() {
            // Elements of a physical group: their nodes join it.
            out.skipped.insert(kind);
            out.other = out.other.saturating_add(usize::try_from(n).unwrap_or(usize::MAX));
            for k in 1..=n {
                let what = || format!("element {k} of {n} of element block {block} (type {kind})");
                b.size(&what)?;
                let mut vertices = Vec::new();
                for _ in 0..corners {
                    let tag = b.size(&what)?;
                    vertices.extend(nodes.index.get(&tag).copied());
                }
                out.add_to_groups(dim, groups, &vertices);
            }
        } else {
            out.skipped.insert(kind);
            out.other = out.other.saturating_add(usize::try_from(n).unwrap_or(usize::MAX));
            let what = || format!("element block {block} of {blocks} ({n} elements of type {kind})");
            b.skip(n, (1 + corners) * size, &what)?;
        }
        total = total.saturating_add(n);
    }
    let end = b.offset;
    b.expect_line("$EndElements", &format!(" (closing '$Elements' at byte offset {at}, which has {blocks} blocks)"))?;
    if total != count {
        return Err(
            b.error(end, format!("$Elements at byte offset {at} says {count} elements, but its blocks hold {total}"))
        );
    }
    Ok(())
}

/// Binary MSH 2.2 `$Nodes`: a count on its own line, then per node an `int` tag and x y z.
fn read_nodes_2_binary<R: BufRead>(b: &mut Binary<'_, R>, nodes: &mut Nodes, at: u64) -> Result<(), IoError> {
    let count = b.count_line("the number of nodes")?;
    nodes.reserve(count);
    for k in 1..=count {
        let offset = b.offset;
        let what = || format!("node {k} of {count} ($Nodes at byte offset {at})");
        let tag = b.int(&what)?;
        let tag =
            u64::try_from(tag).map_err(|_| b.error(offset, format!("node tag {tag} is not a positive integer")))?;
        nodes.add(tag, 0).map_err(|e| b.error(offset, e.to_string()))?;
        nodes.origins.push(b.offset);
        let p = DVec3::new(b.double(&what)?, b.double(&what)?, b.double(&what)?);
        nodes.positions.push(p);
    }
    b.expect_line("$EndNodes", &format!(" (closing '$Nodes' at byte offset {at}, which says {count} nodes)"))
}

/// Binary MSH 2.2 `$Elements`: a count on its own line, then groups of elements of one type:
/// the `int`s `type following tags`, then per element the `int`s `number tag… node…`.
fn read_elements_2_binary<R: BufRead>(
    b: &mut Binary<'_, R>,
    nodes: &Nodes,
    out: &mut Elements,
    at: u64,
) -> Result<(), IoError> {
    let count = b.count_line("the number of elements")?;
    let mut read = 0u64;
    while read < count {
        let start = b.offset;
        let what = || format!("the header of elements {} and on of {count} ($Elements at byte offset {at})", read + 1);
        let [kind, following, tags] = [b.int(&what)?, b.int(&what)?, b.int(&what)?];
        let corners = nodes_per_element(kind)
            .ok_or_else(|| b.error(start, format!("element type {kind} is not a Gmsh element type of fixed size")))?;
        let left = count - read;
        let following = u64::try_from(following).ok().filter(|&f| f > 0 && f <= left).ok_or_else(|| {
            b.error(start + 4, format!("{following} elements follow, expected 1 to the {left} left of {count}"))
        })?;
        let tags = u64::try_from(tags).map_err(|_| b.error(start + 8, format!("number of tags {tags} is negative")))?;
        let dim = element_dim(usize::try_from(kind).unwrap_or(0)).unwrap_or(-1);
        let kind = usize::try_from(kind).unwrap_or(0);
        if kind == TETRAHEDRON || kind == TRIANGLE {
            for k in 1..=following {
                let offset = b.offset;
                let what = || format!("element {} of {count} ($Elements at byte offset {at})", read + k);
                let id = b.int(&what)?;
                let id = u64::try_from(id).map_err(|_| b.error(offset, format!("element tag {id} is negative")))?;
                // The first tag is the physical group (0: none).
                let physical = if tags > 0 { i64::from(b.int(&what)?) } else { 0 };
                b.skip(tags.saturating_sub(1), 4, &what)?;
                let mut v = [0u32; 4];
                for slot in v.iter_mut().take(usize::try_from(corners).unwrap_or(0)) {
                    let tag = b.int(&what)?;
                    let index = u64::try_from(tag).ok().and_then(|t| nodes.index.get(&t).copied());
                    *slot = index.ok_or_else(|| {
                        b.error(offset, format!("element {id}: node tag {tag} is not defined in $Nodes"))
                    })?;
                }
                if physical != 0 {
                    out.add_to_groups(dim, &[physical], &v[..usize::try_from(corners).unwrap_or(0).min(4)]);
                }
                out.push(kind, id, v, offset);
            }
        } else if tags > 0 {
            // The nodes of each element join its physical group.
            out.skipped.insert(kind);
            out.other = out.other.saturating_add(usize::try_from(following).unwrap_or(usize::MAX));
            for k in 1..=following {
                let what = || format!("element {} of {count} ($Elements at byte offset {at})", read + k);
                b.int(&what)?;
                let physical = i64::from(b.int(&what)?);
                b.skip(tags - 1, 4, &what)?;
                let mut vertices = Vec::new();
                for _ in 0..corners {
                    let tag = b.int(&what)?;
                    vertices.extend(u64::try_from(tag).ok().and_then(|t| nodes.index.get(&t).copied()));
                }
                if physical != 0 {
                    out.add_to_groups(dim, &[physical], &vertices);
                }
            }
        } else {
            out.other = out.other.saturating_add(usize::try_from(following).unwrap_or(usize::MAX));
            out.skipped.insert(kind);
            let what = || format!("elements {} to {} of {count} (type {kind})", read + 1, read + following);
            // `tags` comes from an `int`, so the sum cannot overflow.
            b.skip(following, (1 + tags + corners) * 4, &what)?;
        }
        read += following;
    }
    b.expect_line("$EndElements", &format!(" (closing '$Elements' at byte offset {at}, which says {count} elements)"))
}
