//! The sections of an ASCII MSH file, 2.2 and 4.1: `$Nodes` and `$Elements`, line by line.

use std::io::BufRead;
use std::str::SplitWhitespace;

use std::collections::HashMap;

use super::model::{Elements, Nodes, parse_point};
use super::source::element_dim;
use super::{TETRAHEDRON, TRIANGLE};
use crate::io::records::Records;
use crate::io::{IoError, bounded_vec, shown};

/// MSH 2.2 `$Nodes`: a count, then `tag x y z` lines.
pub(super) fn read_nodes_2<R: BufRead>(r: &mut Records<'_, R>, nodes: &mut Nodes) -> Result<(), IoError> {
    let header = r.line;
    r.require_line(|| "the number of nodes".to_owned())?;
    let [count] = r.counts("the number of nodes")?;
    nodes.reserve(count as u64);
    for i in 0..count {
        r.require_line(|| format!("node {} of {count} ($Nodes of line {header})", i + 1))?;
        let fields: Vec<&str> = r.tokens().take(4).collect();
        let tag = nodes.add_text(r, fields.first().copied().unwrap_or(""), 0)?;
        let p = parse_point(fields.get(1..).unwrap_or(&[])).map_err(|m| r.error(format!("node {tag}: {m}")))?;
        nodes.positions.push(p);
        nodes.origins.push(r.line as u64);
    }
    r.expect_line("$EndNodes", &format!(" ($Nodes of line {header} says {count} nodes)"))
}

/// MSH 4.1 `$Nodes`: `blocks nodes min max`, then per block `dim entity parametric n`, `n` tag
/// lines and `n` coordinate lines (parametric coordinates after `x y z` are ignored).
pub(super) fn read_nodes_41<R: BufRead>(r: &mut Records<'_, R>, nodes: &mut Nodes) -> Result<(), IoError> {
    let header = r.line;
    r.require_line(|| "'numEntityBlocks numNodes minNodeTag maxNodeTag'".to_owned())?;
    let [blocks, count, _, _] = r.counts("'numEntityBlocks numNodes minNodeTag maxNodeTag'")?;
    nodes.reserve(count as u64);
    let mut total = 0usize;
    for b in 0..blocks {
        r.require_line(|| format!("node block {} of {blocks} ($Nodes of line {header})", b + 1))?;
        let [_, _, parametric, n] = r.counts("'entityDim entityTag parametric numNodesInBlock'")?;
        if parametric > 1 {
            return Err(r.error(format!("parametric flag {parametric} is not 0 or 1")));
        }
        let mut tags = bounded_vec(n);
        for k in 0..n {
            r.require_line(|| format!("tag {} of {n} of node block {}", k + 1, b + 1))?;
            let mut fields = r.tokens();
            let (Some(tag), None) = (fields.next(), fields.next()) else {
                return Err(r.error(format!("expected one node tag, found '{}'", shown(r.text()))));
            };
            let tag = tag.to_owned();
            tags.push(nodes.add_text(r, &tag, k as u64)?);
        }
        for (k, tag) in tags.iter().enumerate() {
            r.require_line(|| format!("coordinates {} of {n} of node block {}", k + 1, b + 1))?;
            let fields: Vec<&str> = r.tokens().take(3).collect();
            nodes.positions.push(parse_point(&fields).map_err(|m| r.error(format!("node {tag}: {m}")))?);
            nodes.origins.push(r.line as u64);
        }
        total = total.saturating_add(n);
    }
    r.expect_line("$EndNodes", &format!(" ($Nodes of line {header} has {blocks} blocks)"))?;
    if total != count {
        return Err(r.error(format!("$Nodes of line {header} says {count} nodes, but its blocks hold {total}")));
    }
    Ok(())
}

/// `$Elements` of either version. 2.2: a count, then `tag type ntags tag… node…` lines (the
/// first tag is the physical group). 4.1: `blocks elements min max`, then per block `dim entity
/// type n` and `n` lines `tag node…` (the entity's physical groups are in `entities`). The
/// nodes of every element in a physical group, of any type, are added to it.
pub(super) fn read_elements<R: BufRead>(
    r: &mut Records<'_, R>,
    nodes: &Nodes,
    out: &mut Elements,
    v2: bool,
    entities: &HashMap<(i32, i64), Vec<i64>>,
) -> Result<(), IoError> {
    let header = r.line;
    let what = if v2 { "the number of elements" } else { "'numEntityBlocks numElements minElementTag maxElementTag'" };
    r.require_line(|| what.to_owned())?;
    let (blocks, count) = if v2 {
        let [count] = r.counts(what)?;
        (1, count)
    } else {
        let [blocks, count, _, _] = r.counts(what)?;
        (blocks, count)
    };
    let mut total = 0usize;
    let mut groups: Vec<i64> = Vec::new();
    for b in 0..blocks {
        let (block, n) = if v2 {
            (None, count)
        } else {
            r.require_line(|| format!("element block {} of {blocks} ($Elements of line {header})", b + 1))?;
            let [dim, entity, kind, n] = r.counts("'entityDim entityTag elementType numElementsInBlock'")?;
            let (dim, entity) = (i32::try_from(dim).unwrap_or(-1), i64::try_from(entity).unwrap_or(-1));
            (Some((kind, dim, entities.get(&(dim, entity)).cloned().unwrap_or_default())), n)
        };
        for k in 0..n {
            r.require_line(|| format!("element {} of {n} ($Elements of line {header})", k + 1))?;
            let mut tokens = r.tokens();
            let tag = tokens.next().unwrap_or("");
            let (kind, dim) = match &block {
                Some((kind, dim, physical)) => {
                    groups.clone_from(physical);
                    (*kind, *dim)
                }
                None => {
                    let kind = integer_field(r, &mut tokens, "element type")?;
                    let tags = integer_field(r, &mut tokens, "number of tags")?;
                    // Stops at the end of the line, however many tags are claimed.
                    groups.clear();
                    let mut listed = tokens.by_ref().take(tags);
                    if let Some(physical) = listed.next().and_then(|t| t.parse::<i64>().ok()).filter(|&t| t != 0) {
                        groups.push(physical);
                    }
                    listed.for_each(drop);
                    (kind, element_dim(kind).unwrap_or(-1))
                }
            };
            if !groups.is_empty() {
                // Node tags the file does not define are an error below for the elements kept;
                // for the others they only add nothing.
                let vertices: Vec<u32> = tokens.clone().filter_map(|t| nodes.lookup(r, t, tag).ok()).collect();
                out.add_to_groups(dim, &groups, &vertices);
            }
            if kind != TETRAHEDRON && kind != TRIANGLE {
                out.skipped.insert(kind);
                out.other += 1;
                continue;
            }
            // The first four node tags, and how many the line lists (without collecting them all).
            let mut corners = [""; 4];
            let mut listed = 0usize;
            for token in tokens {
                if let Some(slot) = corners.get_mut(listed) {
                    *slot = token;
                }
                listed += 1;
            }
            out.add(r, nodes, kind, tag, &corners[..listed.min(4)], listed)?;
        }
        total = total.saturating_add(n);
    }
    r.expect_line("$EndElements", &format!(" ($Elements of line {header} says {count} elements)"))?;
    if total != count {
        return Err(r.error(format!("$Elements of line {header} says {count} elements, but its blocks hold {total}")));
    }
    Ok(())
}

/// A `$PhysicalNames` line: ((dimension, tag), name).
pub(super) type PhysicalName = ((i32, i64), String);

/// `$PhysicalNames`: a count, then `dim tag "name"` lines, added to `names` (those of earlier
/// sections).
pub(super) fn read_physical_names<R: BufRead>(
    r: &mut Records<'_, R>,
    names: &mut Vec<PhysicalName>,
) -> Result<(), IoError> {
    let header = r.line;
    r.require_line(|| "the number of physical names".to_owned())?;
    let [count] = r.counts("the number of physical names")?;
    names.reserve(count.min(crate::io::MAX_PREALLOCATION));
    for i in 0..count {
        r.require_line(|| format!("physical name {} of {count} ($PhysicalNames of line {header})", i + 1))?;
        add_physical_name(names, r.text()).map_err(|m| r.error(m))?;
    }
    r.expect_line("$EndPhysicalNames", &format!(" ($PhysicalNames of line {header} says {count} names)"))
}

/// Adds the `$PhysicalNames` line `text` to `names` (every section's, ASCII or binary).
///
/// # Errors
/// The message for a malformed line ([`parse_physical_name`]) or a (dimension, tag) that
/// `names` has already.
pub(super) fn add_physical_name(names: &mut Vec<PhysicalName>, text: &str) -> Result<(), String> {
    let name = parse_physical_name(text)?;
    if let Some((_, first)) = names.iter().find(|(key, _)| *key == name.0) {
        let ((dim, tag), _) = name;
        return Err(format!("physical group of dimension {dim} and tag {tag} is named twice (first \"{first}\")"));
    }
    names.push(name);
    Ok(())
}

/// A `$PhysicalNames` line, `dim tag "name"` (the quotes are optional).
///
/// # Errors
/// The message for a line without an integer dimension and tag.
fn parse_physical_name(text: &str) -> Result<PhysicalName, String> {
    let mut tokens = text.trim().splitn(3, char::is_whitespace);
    let (dim, tag) = (tokens.next().and_then(|t| t.parse().ok()), tokens.next().and_then(|t| t.parse().ok()));
    let bad = || format!("expected 'dimension tag \"name\"' (dimension 0 to 3), found '{}'", shown(text));
    let (Some(dim), Some(tag)) = (dim, tag) else { return Err(bad()) };
    if !(0..=3).contains(&dim) {
        return Err(bad());
    }
    let name = tokens.next().unwrap_or("").trim();
    // "a name" whole, or one word without quotes.
    let name = match name.strip_prefix('"') {
        Some(quoted) => quoted.strip_suffix('"').filter(|n| !n.contains('"')).ok_or_else(bad)?,
        None if name.contains(['"', ' ', '\t']) => return Err(bad()),
        None => name,
    };
    Ok(((dim, tag), name.to_owned()))
}

/// MSH 4.1 `$Entities`: `points curves surfaces volumes`, then a line per entity: `tag x y z
/// nphys phys…` for points, `tag minx miny minz maxx maxy maxz nphys phys… nbound bound…` for
/// the others. Returns the physical tags of each (dimension, entity tag).
pub(super) fn read_entities<R: BufRead>(r: &mut Records<'_, R>) -> Result<HashMap<(i32, i64), Vec<i64>>, IoError> {
    let header = r.line;
    r.require_line(|| "'numPoints numCurves numSurfaces numVolumes'".to_owned())?;
    let counts: [usize; 4] = r.counts("'numPoints numCurves numSurfaces numVolumes'")?;
    let mut entities = HashMap::new();
    for (dim, &count) in counts.iter().enumerate() {
        for i in 0..count {
            r.require_line(|| format!("entity {} of {count} of dimension {dim} ($Entities of line {header})", i + 1))?;
            let tokens: Vec<&str> = r.tokens().collect();
            let at = if dim == 0 { 4 } else { 7 };
            let integer = |k: usize| tokens.get(k).and_then(|t| t.parse::<i64>().ok());
            let (Some(tag), Some(n)) = (integer(0), integer(at)) else {
                return Err(r.error(format!("entity line '{}': expected a tag and physical tags", shown(r.text()))));
            };
            let physical: Option<Vec<i64>> =
                (0..usize::try_from(n).unwrap_or(usize::MAX).min(tokens.len())).map(|k| integer(at + 1 + k)).collect();
            let physical =
                physical.ok_or_else(|| r.error(format!("entity {tag}: its physical tags are not integers")))?;
            entities.insert((dim as i32, tag), physical);
        }
    }
    r.expect_line("$EndEntities", &format!(" ($Entities of line {header})"))?;
    Ok(entities)
}

/// The next token of an ASCII 2.2 element line as a non-negative integer; `name` names it in errors.
fn integer_field<R>(r: &Records<'_, R>, tokens: &mut SplitWhitespace<'_>, name: &str) -> Result<usize, IoError> {
    let token = tokens.next().unwrap_or("");
    token.parse::<usize>().map_err(|_| {
        r.error(format!("element line '{}': {name} '{}' is not an integer", shown(r.text()), shown(token)))
    })
}
