//! The text `shapeup info` prints ([`MeshInfo`]'s `Display`).

use std::fmt;

use super::{Found, MeshInfo};

/// `12 (e.g. 3, 40, 77)`, or `0`.
struct Shown<'a, T>(&'a Found<T>, fn(&T) -> String);

impl<T> fmt::Display for Shown<'_, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0.count)?;
        if !self.0.first.is_empty() {
            let shown: Vec<String> = self.0.first.iter().map(self.1).collect();
            let more = if self.0.count > self.0.first.len() { ", …" } else { "" };
            write!(f, " (first: {}{more})", shown.join(", "))?;
        }
        Ok(())
    }
}

fn index(i: &u32) -> String {
    i.to_string()
}

fn pair(e: &[u32; 2]) -> String {
    format!("{}–{}", e[0], e[1])
}

fn triple(v: &[f64; 3]) -> String {
    format!("({}, {}, {})", number(v[0]), number(v[1]), number(v[2]))
}

/// Six significant digits, without trailing noise.
fn number(x: f64) -> String {
    if x == 0.0 || (1e-4..1e7).contains(&x.abs()) {
        let digits = (5 - x.abs().log10().floor().max(-5.0) as i32).clamp(0, 10) as usize;
        let s = format!("{x:.digits$}");
        if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
    } else {
        let s = format!("{x:.5e}");
        match s.split_once('e') {
            Some((mantissa, exponent)) if mantissa.contains('.') => {
                format!("{}e{exponent}", mantissa.trim_end_matches('0').trim_end_matches('.'))
            }
            _ => s,
        }
    }
}

fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// The summary `shapeup info` prints: one aspect per line, a label then the values; element
/// indices are 0-based as in scenes.
impl fmt::Display for MeshInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (c, s, d) = (&self.counts, &self.surface, &self.degenerate);
        writeln!(f, "vertices:        {} ({} unreferenced)", c.vertices, c.unreferenced_vertices)?;
        write!(
            f,
            "faces:           {}: {}, {}, {}",
            c.faces,
            plural(c.triangles, "triangle", "triangles"),
            plural(c.quads, "quad", "quads"),
            plural(c.ngons, "n-gon", "n-gons")
        )?;
        if c.faces_under_3_corners > 0 {
            write!(f, ", {} with 1 or 2 corners", c.faces_under_3_corners)?;
        }
        writeln!(f)?;
        write!(f, "triangulation:   {}", plural(c.triangulation_triangles, "triangle", "triangles"))?;
        if c.faces_not_triangulated > 0 {
            write!(f, " ({} not triangulated)", plural(c.faces_not_triangulated, "face", "faces"))?;
        }
        writeln!(f)?;
        writeln!(f, "tetrahedra:      {}", c.tetrahedra)?;
        writeln!(f, "edges:           {}", c.edges)?;
        writeln!(
            f,
            "pieces:          {} (largest: {} vertices)",
            self.pieces.pieces, self.pieces.largest_piece_vertices
        )?;
        writeln!(
            f,
            "boundary:        {}, {}{}",
            plural(s.boundary_loops, "loop", "loops"),
            plural(s.boundary_edges, "edge", "edges"),
            if s.closed { " (closed surface)" } else { "" }
        )?;
        writeln!(f, "non-manifold:    edges in 3+ faces {}", Shown(&s.non_manifold_edges, pair))?;
        writeln!(f, "                 vertices (not one fan) {}", Shown(&s.non_manifold_vertices, index))?;
        writeln!(
            f,
            "orientation:     edges run the same way by both faces {}",
            Shown(&s.inconsistent_orientation_edges, pair)
        )?;
        write!(
            f,
            "topology:        V − E + F = {} − {} + {} = χ {}",
            s.vertices, s.edges, s.faces, s.euler_characteristic
        )?;
        match s.genus {
            Some(g) => writeln!(f, ", genus {g}")?,
            None => writeln!(f, ", genus not defined (not an oriented manifold)")?,
        }
        writeln!(f, "surface area:    {}", number(s.area))?;
        if let Some(v) = &self.volume {
            writeln!(
                f,
                "volume:          {}; boundary {} faces, {}, {} open edges, {} non-manifold edges; {} faces in 3+ tetrahedra",
                number(v.volume),
                v.boundary_faces,
                if v.boundary_closed { "closed" } else { "not closed" },
                v.boundary_open_edges,
                v.boundary_non_manifold_edges,
                v.faces_in_more_than_two_tetrahedra
            )?;
        }
        writeln!(
            f,
            "degenerate:      zero-area faces {} (area ≤ {})",
            Shown(&d.zero_area_faces, index),
            number(d.area_tolerance)
        )?;
        writeln!(f, "                 zero-area triangles {}", Shown(&d.zero_area_triangles, index))?;
        writeln!(f, "                 faces repeating a corner {}", Shown(&d.faces_repeating_a_corner, index))?;
        writeln!(
            f,
            "                 zero-length edges {} (length ≤ {})",
            Shown(&d.zero_length_edges, pair),
            number(d.length_tolerance)
        )?;
        if c.tetrahedra > 0 {
            writeln!(
                f,
                "                 flat tetrahedra {} (|volume| ≤ {})",
                Shown(&d.flat_tetrahedra, index),
                number(d.volume_tolerance)
            )?;
            writeln!(f, "                 inverted tetrahedra {}", Shown(&d.inverted_tetrahedra, index))?;
            if let Some(v) = self.volume.as_ref().filter(|v| v.left_handed_tetrahedra.count > 0) {
                writeln!(
                    f,
                    "                 left-handed tetrahedra in the file {} (solved right-handed, written back as the file lists them)",
                    Shown(&v.left_handed_tetrahedra, index)
                )?;
            }
        }
        if !self.physical_groups.is_empty() {
            let groups: Vec<String> = self
                .physical_groups
                .iter()
                .map(|g| format!("\"{}\" (dimension {}, tag {}, {} vertices)", g.name, g.dimension, g.tag, g.vertices))
                .collect();
            writeln!(f, "physical groups: {}", groups.join(", "))?;
        }
        let b = &self.bounding_box;
        writeln!(f, "bounding box:    min {} max {}", triple(&b.min), triple(&b.max))?;
        writeln!(f, "size:            {}, diagonal {}", triple(&b.size), number(b.diagonal))?;
        write!(f, "units (a guess): {}", self.units_guess)
    }
}
