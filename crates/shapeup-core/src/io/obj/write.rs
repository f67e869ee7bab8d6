//! Writing OBJ: a mesh read from OBJ gets its file back line for line ([`write_lines`]); any other
//! mesh a new file ([`write_new`]).

use std::io::{self, Write};

use super::attributes::{ObjAttributes, ObjLine, fingerprint};
use glam::DVec3;

use crate::geometry::indexed_normals;
use crate::io::attributes::{AttributeKind, NO_INDEX};
use crate::io::{Attributes, UTF8_BOM, report_dropped, write_f64, write_xyz};
use crate::mesh::Mesh;
use crate::warnings::Warnings;

/// Writes `mesh` as OBJ. A mesh read from OBJ whose vertices and faces still match the file
/// comes out line for line (see the [module docs](super)), its used normals recomputed (counted
/// in `warnings`); any other mesh as a new file: one `v` line per vertex (with its colour when
/// the attributes have colours), the texture coordinates, smooth per-vertex normals when the
/// attributes have normals, and one 1-based `f` line per polygon. Tetrahedra are not written.
///
/// # Errors
/// Any error of `w`.
pub fn write_obj(w: &mut dyn Write, mesh: &Mesh, attributes: &Attributes, warnings: &mut Warnings) -> io::Result<()> {
    let mut same_faces = true;
    if let Attributes::Obj(obj) = attributes {
        match obj.mismatch(mesh) {
            None => return write_lines(w, mesh, obj, warnings),
            Some(reason) => warnings.add(
                "obj_lines_not_kept",
                "meshes whose vertices or faces no longer match their OBJ file's lines, written as new OBJ \
                 files (the file's comments, groups and layout are not kept)",
                || reason,
            ),
        }
        // Per-corner texture indices only mean something for the faces they were read with.
        same_faces = obj.polygons_fingerprint == fingerprint(&mesh.polygons);
    }
    write_new(w, mesh, attributes, same_faces, warnings)
}

/// Writes a kept line's bytes, which may span physical lines (`\n` inside), with the file's line
/// ending; returns how many physical lines they span.
fn write_text(w: &mut dyn Write, text: &[u8], newline: &[u8]) -> io::Result<usize> {
    let mut count = 0;
    for (k, part) in text.split(|&b| b == b'\n').enumerate() {
        if k > 0 {
            w.write_all(newline)?;
        }
        w.write_all(part)?;
        count += 1;
    }
    Ok(count)
}

/// The file's lines with the mesh's positions and recomputed normals.
fn write_lines(w: &mut dyn Write, mesh: &Mesh, obj: &ObjAttributes, warnings: &mut Warnings) -> io::Result<()> {
    let newline: &[u8] = if obj.crlf { b"\r\n" } else { b"\n" };
    let normals = if obj.normals.is_empty() {
        Vec::new()
    } else {
        indexed_normals(&mesh.positions, &mesh.polygons, &obj.corner_normals, obj.normals.len())
    };
    if obj.bom {
        w.write_all(UTF8_BOM)?;
    }
    let mut line_number = 1;
    let mut recomputed = 0;
    let mut first_recomputed = String::new();
    for (k, line) in obj.lines.iter().enumerate() {
        if k > 0 {
            w.write_all(newline)?;
        }
        match line {
            ObjLine::Vertex { index, rest } => {
                let p = mesh.positions.get(*index as usize).copied().unwrap_or_default();
                w.write_all(b"v ")?;
                write_xyz(w, p)?;
                line_number += write_text(w, rest, newline)?;
            }
            ObjLine::Normal { index, text } => match normals.get(*index as usize).copied().flatten() {
                Some(n) => {
                    if recomputed == 0 {
                        first_recomputed = format!("vn {} (line {line_number})", u64::from(*index) + 1);
                    }
                    recomputed += 1;
                    w.write_all(b"vn ")?;
                    write_xyz(w, n)?;
                    line_number += 1;
                }
                None => line_number += write_text(w, text, newline)?,
            },
            ObjLine::Other(text) => line_number += write_text(w, text, newline)?,
        }
    }
    if obj.final_newline {
        w.write_all(newline)?;
    }
    warnings
        .add_many("normals_recomputed", "normals recomputed from the moved geometry", recomputed, || first_recomputed);
    Ok(())
}

/// A new OBJ file for a mesh without (matching) OBJ lines; texture coordinates only when its
/// attributes belong to its faces (`same_faces`).
fn write_new(
    w: &mut dyn Write,
    mesh: &Mesh,
    attributes: &Attributes,
    same_faces: bool,
    warnings: &mut Warnings,
) -> io::Result<()> {
    let n = mesh.num_vertices();
    let polygons = &mesh.polygons;
    writeln!(w, "# written by shapeup: {n} vertices, {} faces", mesh.num_polygons())?;
    let colors = attributes.vertex_colors().filter(|c| c.len() == n);
    for (i, p) in mesh.positions.iter().enumerate() {
        w.write_all(b"v ")?;
        write_xyz(w, *p)?;
        if let Some(c) = colors.as_ref().and_then(|c| c.get(i)) {
            w.write_all(b" ")?;
            write_xyz(w, DVec3::from_array(*c))?;
        }
        w.write_all(b"\n")?;
    }
    let texcoords = attributes.texcoords(polygons).filter(|t| same_faces && t.corners.len() == polygons.num_corners());
    if let Some(t) = &texcoords {
        for [u, v] in &t.values {
            w.write_all(b"vt ")?;
            write_f64(w, *u)?;
            w.write_all(b" ")?;
            write_f64(w, *v)?;
            w.write_all(b"\n")?;
        }
    }
    // Smooth normals, one per vertex some polygon uses (`vn` k+1 for the vertex with index k).
    let mut normal_of_vertex = vec![NO_INDEX; if attributes.has_normals() { n } else { 0 }];
    if attributes.has_normals() {
        let mut written = 0u32;
        for (v, normal) in indexed_normals(&mesh.positions, polygons, polygons.indices(), n).iter().enumerate() {
            if let Some(normal) = normal {
                w.write_all(b"vn ")?;
                write_xyz(w, *normal)?;
                w.write_all(b"\n")?;
                normal_of_vertex[v] = written;
                written += 1;
            }
        }
        let vt_lines = texcoords.as_ref().map_or(0, |t| t.values.len());
        warnings.add_many("normals_recomputed", "normals recomputed from the moved geometry", written as usize, || {
            format!("vn 1 (line {})", 2 + n + vt_lines)
        });
    }
    for (face, poly) in polygons.iter().enumerate() {
        let range = polygons.corner_range(face);
        // A face's corners must all have a vt (vn) index or none: else the face goes without.
        let t_of = |c: usize| {
            texcoords.as_ref().and_then(|t| t.corners.get(c).copied().filter(|&i| (i as usize) < t.values.len()))
        };
        let n_of = |v: u32| normal_of_vertex.get(v as usize).copied().filter(|&i| i != NO_INDEX);
        let with_t = range.clone().all(|c| t_of(c).is_some());
        let with_n = !normal_of_vertex.is_empty() && poly.iter().all(|&v| n_of(v).is_some());
        w.write_all(b"f")?;
        for (c, &v) in range.zip(poly) {
            write!(w, " {}", u64::from(v) + 1)?;
            match (with_t, with_n) {
                (false, false) => {}
                (true, false) => write!(w, "/{}", t_of(c).map_or(0, |i| u64::from(i) + 1))?,
                (false, true) => write!(w, "//{}", n_of(v).map_or(0, |i| u64::from(i) + 1))?,
                (true, true) => write!(
                    w,
                    "/{}/{}",
                    t_of(c).map_or(0, |i| u64::from(i) + 1),
                    n_of(v).map_or(0, |i| u64::from(i) + 1)
                )?,
            }
        }
        w.write_all(b"\n")?;
    }
    let mut kept = Vec::new();
    if texcoords.is_some() {
        kept.push(AttributeKind::TexCoords);
    }
    if colors.is_some() {
        kept.push(AttributeKind::VertexColors);
    }
    if attributes.has_normals() {
        kept.push(AttributeKind::Normals);
    }
    report_dropped(attributes, &kept, "OBJ", warnings);
    Ok(())
}
