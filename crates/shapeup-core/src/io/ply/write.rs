//! Writing PLY: a mesh read from PLY gets its file back, property by property ([`write_own`]);
//! any other mesh gets shapeup's own layout ([`write_generic`]).

use std::io::{self, Write};

use glam::DVec3;

use super::attributes::{PlyAttributes, PlyType};
use super::scalar::{PlyEncoding, PlyScalar};
use crate::io::attributes::AttributeKind;
use crate::io::{Attributes, recompute_vertex_normals, report_dropped};
use crate::mesh::Mesh;
use crate::warnings::Warnings;

/// Writes `mesh` as PLY in `encoding` (`None`: the input's own, else binary little endian).
///
/// A mesh read from PLY whose vertex count and polygons are still the file's gets the file back
/// (see the [module docs](super)): every element and property with its type, only x y z and any
/// `nx ny nz` (recomputed, counted as `normals_recomputed`) changed. Otherwise: `double` x y z,
/// `float` nx ny nz if the attributes have normals (recomputed), `uchar` red green blue if they
/// have vertex colours (a warning when a colour is not a multiple of 1/255), the polygons as
/// `list uchar int vertex_indices` (a wider count type for polygons of more than 255 corners),
/// per-corner `list uchar float texcoord` when every corner has texture coordinates, and a
/// warning for what else the attributes hold. Tetrahedra are not written.
///
/// # Errors
/// Any error of `w`; [`io::ErrorKind::InvalidInput`] for more than `i32::MAX` vertices in a new
/// file (the indices are `int`).
pub fn write_ply(
    w: &mut dyn Write,
    mesh: &Mesh,
    attributes: &Attributes,
    encoding: Option<PlyEncoding>,
    warnings: &mut Warnings,
) -> io::Result<()> {
    if let Attributes::Ply(own) = attributes {
        let encoding = encoding.unwrap_or(own.encoding);
        match own.mismatch(mesh) {
            None => return write_own(w, mesh, own, encoding, warnings),
            Some(why) => {
                warnings.add(
                    "ply_layout_not_kept",
                    "PLY inputs that no longer match the mesh, written with its positions, faces and common attributes only",
                    || why,
                );
                return write_generic(w, mesh, attributes, encoding, warnings);
            }
        }
    }
    write_generic(w, mesh, attributes, encoding.unwrap_or(PlyEncoding::BinaryLittleEndian), warnings)
}

/// Appends one value of type `ty` to an instance being encoded.
fn put(out: &mut Vec<u8>, ty: PlyScalar, v: f64, encoding: PlyEncoding) -> io::Result<()> {
    match encoding {
        PlyEncoding::Ascii => {
            if !out.is_empty() {
                out.push(b' ');
            }
            ty.write_ascii(v, out)
        }
        PlyEncoding::BinaryLittleEndian => {
            ty.encode(v, false, out);
            Ok(())
        }
        PlyEncoding::BinaryBigEndian => {
            ty.encode(v, true, out);
            Ok(())
        }
    }
}

/// Writes the file `own` describes, with `mesh`'s positions and recomputed normals.
fn write_own(
    w: &mut dyn Write,
    mesh: &Mesh,
    own: &PlyAttributes,
    encoding: PlyEncoding,
    warnings: &mut Warnings,
) -> io::Result<()> {
    let mut head = String::from("ply\n");
    for line in &own.header {
        let mut tokens = line.split_whitespace();
        if encoding != own.encoding && tokens.next() == Some("format") {
            let version = tokens.nth(1).unwrap_or("1.0");
            head.push_str(&format!("format {} {version}", encoding.keyword()));
        } else {
            head.push_str(line);
        }
        head.push('\n');
    }
    head.push_str("end_header\n");
    w.write_all(head.as_bytes())?;

    let (vertex_element, xyz) = own.plan.vertex;
    let normal_properties = own.normal_properties();
    let normals = match normal_properties {
        Some(_) => recompute_vertex_normals(mesh, warnings),
        None => Vec::new(),
    };
    let mut rounded = 0;
    let mut first_rounded = None;
    let mut out = Vec::new();
    for (e, element) in own.elements.iter().enumerate() {
        if element.properties.is_empty() {
            continue;
        }
        for i in 0..element.count {
            out.clear();
            for (p, property) in element.properties.iter().enumerate() {
                match property.ty {
                    PlyType::Scalar(ty) => {
                        let mut v = property.scalar(i).unwrap_or(0.0);
                        if e == vertex_element {
                            if let Some(axis) = xyz.iter().position(|&q| q == p) {
                                v = mesh.positions.get(i).and_then(|q| q.to_array().get(axis).copied()).unwrap_or(v);
                                // Only integer types lose more than their declared precision.
                                if ty.is_integer() && ty.coerce(v) != v {
                                    rounded += 1;
                                    first_rounded.get_or_insert(i);
                                }
                            } else if let Some(axis) = normal_properties.and_then(|n| n.iter().position(|&q| q == p))
                                && let Some(Some(normal)) = normals.get(i)
                            {
                                v = normal.to_array().get(axis).copied().unwrap_or(v);
                            }
                        }
                        put(&mut out, ty, v, encoding)?;
                    }
                    PlyType::List { count, item } => {
                        let items = property.list(i).unwrap_or(&[]);
                        put(&mut out, count, items.len() as f64, encoding)?;
                        for &v in items {
                            put(&mut out, item, v, encoding)?;
                        }
                    }
                }
            }
            if encoding == PlyEncoding::Ascii {
                out.push(b'\n');
            }
            w.write_all(&out)?;
        }
    }
    if let Some(first) = first_rounded {
        warnings.add_many(
            "coordinates_rounded",
            "coordinates rounded to the file's integer coordinate types",
            rounded,
            || format!("vertex {first}"),
        );
    }
    Ok(())
}

/// The smallest integer type that holds `n`.
fn count_type(n: usize) -> PlyScalar {
    if n <= usize::from(u8::MAX) {
        PlyScalar::UChar
    } else if n <= usize::from(u16::MAX) {
        PlyScalar::UShort
    } else {
        PlyScalar::UInt
    }
}

/// Writes `mesh` in the layout shapeup chooses (see [`write_ply`]).
fn write_generic(
    w: &mut dyn Write,
    mesh: &Mesh,
    attributes: &Attributes,
    encoding: PlyEncoding,
    warnings: &mut Warnings,
) -> io::Result<()> {
    let n = mesh.num_vertices();
    if i32::try_from(n).is_err() {
        return Err(io::Error::new(io::ErrorKind::InvalidInput, "PLY 'int' indices allow at most i32::MAX vertices"));
    }
    let mut kept = Vec::new();
    if attributes.has_normals() {
        kept.push(AttributeKind::Normals);
    }
    let colors = attributes.vertex_colors().filter(|c| c.len() == n);
    if colors.is_some() {
        kept.push(AttributeKind::VertexColors);
    }
    let texcoords = attributes.texcoords(&mesh.polygons).filter(|t| {
        t.corners.len() == mesh.polygons.num_corners() && t.corners.iter().all(|&c| (c as usize) < t.values.len())
    });
    if texcoords.is_some() {
        kept.push(AttributeKind::TexCoords);
    }
    report_dropped(attributes, &kept, "PLY", warnings);
    let normals = attributes.has_normals().then(|| recompute_vertex_normals(mesh, warnings));
    let colors: Option<Vec<[f64; 3]>> = colors.map(|colors| {
        let mut rounded = colors.iter().enumerate().filter(|(_, c)| {
            c.iter().any(|&c| {
                let byte = PlyScalar::UChar.coerce(c * 255.0);
                byte / 255.0 != c
            })
        });
        if let Some((first, _)) = rounded.next() {
            warnings.add_many("colors_rounded", "vertex colours rounded to 8 bits", 1 + rounded.count(), || {
                format!("vertex {first}")
            });
        }
        colors.iter().map(|c| c.map(|c| c * 255.0)).collect()
    });

    let max_corners = mesh.polygons.iter().map(<[u32]>::len).max().unwrap_or(0);
    let index_count = count_type(max_corners);
    let texcoord_count = count_type(2 * max_corners);
    let mut head = format!(
        "ply\nformat {} 1.0\ncomment written by shapeup\nelement vertex {n}\nproperty double x\nproperty double y\nproperty double z\n",
        encoding.keyword()
    );
    if normals.is_some() {
        head.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    if colors.is_some() {
        head.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
    }
    head.push_str(&format!(
        "element face {}\nproperty list {} int vertex_indices\n",
        mesh.num_polygons(),
        index_count.name()
    ));
    if texcoords.is_some() {
        head.push_str(&format!("property list {} float texcoord\n", texcoord_count.name()));
    }
    head.push_str("end_header\n");
    w.write_all(head.as_bytes())?;

    let mut out = Vec::new();
    for (i, p) in mesh.positions.iter().enumerate() {
        out.clear();
        for x in p.to_array() {
            put(&mut out, PlyScalar::Double, x, encoding)?;
        }
        if let Some(normals) = &normals {
            let normal = normals.get(i).copied().flatten().unwrap_or(DVec3::ZERO);
            for x in normal.to_array() {
                put(&mut out, PlyScalar::Float, x, encoding)?;
            }
        }
        if let Some(colors) = &colors {
            for x in colors.get(i).copied().unwrap_or_default() {
                put(&mut out, PlyScalar::UChar, x, encoding)?;
            }
        }
        if encoding == PlyEncoding::Ascii {
            out.push(b'\n');
        }
        w.write_all(&out)?;
    }
    for (f, poly) in mesh.polygons.iter().enumerate() {
        out.clear();
        put(&mut out, index_count, poly.len() as f64, encoding)?;
        for &v in poly {
            put(&mut out, PlyScalar::Int, f64::from(v), encoding)?;
        }
        if let Some(t) = &texcoords {
            let corners = t.corners.get(mesh.polygons.corner_range(f)).unwrap_or(&[]);
            put(&mut out, texcoord_count, 2.0 * corners.len() as f64, encoding)?;
            for &c in corners {
                for x in t.values.get(c as usize).copied().unwrap_or_default() {
                    put(&mut out, PlyScalar::Float, x, encoding)?;
                }
            }
        }
        if encoding == PlyEncoding::Ascii {
            out.push(b'\n');
        }
        w.write_all(&out)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use std::path::Path;

    use crate::io::ply::read_ply;

    #[test]
    fn huge_element_without_properties_is_skipped_at_once() {
        for format in ["ascii", "binary_little_endian"] {
            let text = format!(
                "ply\nformat {format} 1.0\nelement nothing 18446744073709551615\nelement vertex 1\nproperty uchar x\nproperty uchar y\nproperty uchar z\nend_header\n"
            );
            let mut bytes = text.into_bytes();
            bytes.extend_from_slice(if format == "ascii" { b"1 2 3\n" } else { &[1, 2, 3] });
            let loaded = read_ply(&bytes[..], Path::new("n.ply")).unwrap();
            assert_eq!(loaded.mesh.positions, vec![DVec3::new(1.0, 2.0, 3.0)]);
            // And it is written back as it was: declared, without data.
            let mut out = Vec::new();
            write_ply(&mut out, &loaded.mesh, &loaded.attributes, None, &mut Warnings::new()).unwrap();
            assert_eq!(out, bytes);
        }
    }

    #[test]
    fn integer_coordinates_are_rounded_with_a_warning() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty short x\nproperty short y\nproperty short z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        let loaded = read_ply(text.as_bytes(), Path::new("n.ply")).unwrap();
        let moved = loaded.mesh.with_positions(vec![DVec3::new(0.4, 0.0, 0.0), DVec3::new(7.0, 0.0, 0.0), DVec3::Y]);
        let mut out = Vec::new();
        let mut warnings = Warnings::new();
        write_ply(&mut out, &moved, &loaded.attributes, None, &mut warnings).unwrap();
        let back = read_ply(&out[..], Path::new("n.ply")).unwrap();
        assert_eq!(back.mesh.positions, vec![DVec3::ZERO, DVec3::new(7.0, 0.0, 0.0), DVec3::Y]);
        assert_eq!(warnings.count("coordinates_rounded"), 1);
    }
}
