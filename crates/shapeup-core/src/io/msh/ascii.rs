//! The sections of an ASCII MSH file, 2.2 and 4.1: `$Nodes` and `$Elements`, line by line.

use std::io::BufRead;
use std::str::SplitWhitespace;

use super::model::{Elements, Nodes, parse_point};
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
        }
        total = total.saturating_add(n);
    }
    r.expect_line("$EndNodes", &format!(" ($Nodes of line {header} has {blocks} blocks)"))?;
    if total != count {
        return Err(r.error(format!("$Nodes of line {header} says {count} nodes, but its blocks hold {total}")));
    }
    Ok(())
}

/// `$Elements` of either version. 2.2: a count, then `tag type ntags tag… node…` lines. 4.1:
/// `blocks elements min max`, then per block `dim entity type n` and `n` lines `tag node…`.
pub(super) fn read_elements<R: BufRead>(
    r: &mut Records<'_, R>,
    nodes: &Nodes,
    out: &mut Elements,
    v2: bool,
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
    for b in 0..blocks {
        let (kind, n) = if v2 {
            (None, count)
        } else {
            r.require_line(|| format!("element block {} of {blocks} ($Elements of line {header})", b + 1))?;
            let [_, _, kind, n] = r.counts("'entityDim entityTag elementType numElementsInBlock'")?;
            (Some(kind), n)
        };
        for k in 0..n {
            r.require_line(|| format!("element {} of {n} ($Elements of line {header})", k + 1))?;
            let mut tokens = r.tokens();
            let tag = tokens.next().unwrap_or("");
            let kind = match kind {
                Some(kind) => kind,
                None => {
                    let kind = integer_field(r, &mut tokens, "element type")?;
                    let tags = integer_field(r, &mut tokens, "number of tags")?;
                    // Stops at the end of the line, however many tags are claimed.
                    tokens.by_ref().take(tags).for_each(drop);
                    kind
                }
            };
            if kind != TETRAHEDRON && kind != TRIANGLE {
                out.skipped.insert(kind);
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

/// The next token of an ASCII 2.2 element line as a non-negative integer; `name` names it in errors.
fn integer_field<R>(r: &Records<'_, R>, tokens: &mut SplitWhitespace<'_>, name: &str) -> Result<usize, IoError> {
    let token = tokens.next().unwrap_or("");
    token.parse::<usize>().map_err(|_| {
        r.error(format!("element line '{}': {name} '{}' is not an integer", shown(r.text()), shown(token)))
    })
}
