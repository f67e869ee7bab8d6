//! Wavefront OBJ, kept line for line.
//!
//! Hand-written rather than `tobj`, which drops unreferenced vertices and reorders them when it
//! merges position/normal/texture indices, and keeps no lines: here vertex *i* of the mesh is the
//! *i*-th `v` line, and every line of the file is kept.
//!
//! **Read.** `v x y z [w | r g b [a]]`; `vt u [v [w]]`; `vn x y z`; `f` with `i`, `i/t`, `i//n`
//! or `i/t/n` corners (all corners of a face of one form), 1-based or negative (relative to the
//! last `v`, `vt` or `vn` read so far), any number of corners (triangulated by
//! [`Mesh::from_polygons`](crate::mesh::Mesh::from_polygons)); `#` comments, `\` line continuations, `\r\n` endings, a UTF-8
//! byte-order mark; UTF-16 files (byte-order mark) are decoded and read as their UTF-8 copy (and
//! written back as UTF-8). Values after a vertex's x y z are a colour when there are 3 or 4 of them,
//! all numbers (`r g b` or `r g b a`: colours come first, as MeshLab and tinyobjloader write and
//! read them); 1 (`w`), 2 or 5 and more are not. The file has vertex colours when every `v`
//! line has one.
//!
//! **Kept** ([`ObjAttributes`]): every logical line in order — for a `v` line the text after its
//! z coordinate (w, colour, comment) verbatim, for a `vn` line the line itself, every other line
//! (comments, blank lines, `vt`, `f`, `o`, `g`, `s`, `mtllib`, `usemtl`, `l`, `p`, unknown
//! directives) verbatim — with the parsed texture coordinates, normals, per-corner `vt` and `vn`
//! indices, colours, the line-ending style (that of the first line), whether the file ends with a
//! newline and whether it starts with a byte-order mark. Lines are kept as the file's bytes, so
//! text that is not UTF-8 (Latin-1 comments, group and material names of older files) comes back
//! unchanged and `usemtl` names still match the `.mtl` file; only numbers, indices and keywords
//! are parsed, and those are ASCII.
//!
//! **Written back** as OBJ the file comes out line for line, byte for byte, except that each `v`
//! line becomes `v x y z` (the new position, shortest exact decimals) followed by its original
//! rest, and each normal some face corner uses is recomputed from the new geometry with the
//! file's own corner→normal indexing (so hard edges and smoothing groups stay), angle-weighted
//! ([`indexed_normals`](crate::geometry::indexed_normals)); a `\` continuation inside a vertex's (or a recomputed normal's)
//! coordinates is joined. Material (`.mtl`) files are never touched. A mesh without OBJ lines (or
//! whose vertices or faces no longer match them) is written as a new file: a header comment, `v`
//! (with colours), `vt`, per-vertex `vn` and one `f` line per polygon.

mod attributes;
mod lines;
mod read;
mod write;

pub use attributes::{ObjAttributes, ObjLine};
pub use read::read_obj;
pub use write::write_obj;

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use std::path::Path;

    use glam::DVec3;

    use crate::io::{Attributes, IoError, LoadedMesh};
    use crate::mesh::{Mesh, Polygons};
    use crate::warnings::Warnings;

    fn read(text: &str) -> Result<LoadedMesh, IoError> {
        read_obj(text.as_bytes(), Path::new("mem.obj"))
    }

    fn obj(attributes: &Attributes) -> &ObjAttributes {
        match attributes {
            Attributes::Obj(a) => a,
            other => panic!("not OBJ attributes: {other:?}"),
        }
    }

    fn write(mesh: &Mesh, attributes: &Attributes) -> (String, Warnings) {
        let mut out = Vec::new();
        let mut warnings = Warnings::new();
        write_obj(&mut out, mesh, attributes, &mut warnings).unwrap();
        (String::from_utf8(out).unwrap(), warnings)
    }

    #[test]
    fn continuation_comments_and_unknown_directives() {
        let text = "# c\nv 0 0 0 # inline\nv 1 0 0\r\nv 0 \\\n 1 0\nvn 0 0 1\nfoo bar\nf 1 2 \\\n3\n";
        let loaded = read(text).unwrap();
        assert_eq!(loaded.mesh.positions[2], DVec3::Y);
        assert_eq!(loaded.mesh.triangles, vec![[0, 1, 2]]);
        let a = obj(&loaded.attributes);
        assert_eq!(a.lines[1], ObjLine::Vertex { index: 0, rest: " # inline".into() });
        assert_eq!(a.lines[6], ObjLine::Other("f 1 2 \\\n3".into()));
        assert!(!a.crlf && a.final_newline && !a.bom);
    }

    #[test]
    fn error_on_continued_line_names_its_first_line() {
        let err = read("v 0 0 0\nv 1 \\\n x 0\n").unwrap_err().to_string();
        assert!(err.contains("mem.obj: line 2:") && err.contains("'x'"), "{err}");
    }

    #[test]
    fn file_without_trailing_newline_and_backslash_at_end() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 \\";
        let loaded = read(text).unwrap();
        assert_eq!(loaded.mesh.triangles.len(), 1);
        assert!(!obj(&loaded.attributes).final_newline);
        assert_eq!(
            write(&loaded.mesh, &loaded.attributes).0,
            "v 0.0 0.0 0.0\nv 1.0 0.0 0.0\nv 0.0 1.0 0.0\nf 1 2 3 \\"
        );
    }

    #[test]
    fn w_and_colours_are_told_apart_by_count() {
        let colors = |rest: &str| {
            let text = format!("v 0 0 0{rest}\nv 1 0 0{rest}\nv 0 1 0{rest}\nf 1 2 3\n");
            obj(&read(&text).unwrap().attributes).colors.clone()
        };
        assert_eq!(colors(" 1"), None, "w");
        assert_eq!(colors(" 0.5 0.25"), None);
        assert_eq!(colors(" 0.5 0.25 1"), Some(vec![[0.5, 0.25, 1.0]; 3]));
        assert_eq!(colors(" 0.5 0.25 1 0.9"), Some(vec![[0.5, 0.25, 1.0]; 3]), "r g b a");
        assert_eq!(colors(" 1 0.5 0.25 1 0.9"), None);
        assert_eq!(colors(" red green blue"), None);
        // Only when every vertex has one.
        let loaded = read("v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 0 1\nf 1 2 3\n").unwrap();
        assert_eq!(loaded.attributes.vertex_colors(), None);
        // 0–255 colours are scaled into [0, 1].
        let loaded = read("v 0 0 0 255 0 51\nv 1 0 0 0 255 0\nv 0 1 0 0 0 255\nf 1 2 3\n").unwrap();
        assert_eq!(loaded.attributes.vertex_colors().unwrap()[0], [1.0, 0.0, 0.2]);
    }

    #[test]
    fn mixed_corner_forms_are_errors() {
        let base = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";
        let err = read(&format!("{base}f 1/1 2 3/1\n")).unwrap_err().to_string();
        assert!(err.contains("line 6") && err.contains("vt count mismatch") && err.contains("'2'"), "{err}");
        let err = read(&format!("{base}f 1//1 2//1 3\n")).unwrap_err().to_string();
        assert!(err.contains("line 6") && err.contains("vn count mismatch") && err.contains("'3'"), "{err}");
    }

    #[test]
    fn writes_one_based_faces() {
        let mesh = Mesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]).unwrap();
        let (text, warnings) = write(&mesh, &Attributes::None);
        assert!(text.contains("v 1.0 0.0 0.0\n") && text.ends_with("f 1 2 3\n"), "{text}");
        assert!(warnings.is_empty());
    }

    #[test]
    fn unchanged_file_is_reproduced_and_moved_vertices_keep_their_rest() {
        let text = "\u{feff}# hi\r\nv 0 0 0 1 0 0 # red\r\nv 1 0 0 0 1 0\r\nv 0 1 0 0 0 1\r\nvt 0 0\r\n\r\n\
                    vn 0 0 1\r\nvn 1 0 0\r\ng a\r\nf 1/1/1 2/1/1 3/1/1\r\n";
        let loaded = read(text).unwrap();
        let mut moved = loaded.mesh.clone();
        moved.positions[1] = DVec3::new(2.0, 0.0, 0.0);
        let (out, warnings) = write(&moved, &loaded.attributes);
        let expected = "\u{feff}# hi\r\nv 0.0 0.0 0.0 1 0 0 # red\r\nv 2.0 0.0 0.0 0 1 0\r\nv 0.0 1.0 0.0 0 0 1\r\n\
                        vt 0 0\r\n\r\nvn 0.0 0.0 1.0\r\nvn 1 0 0\r\ng a\r\nf 1/1/1 2/1/1 3/1/1\r\n";
        assert_eq!(out, expected, "the unused vn 2 keeps its line");
        assert_eq!(warnings.count("normals_recomputed"), 1);
        assert_eq!(warnings.iter().next().unwrap().first, "vn 1 (line 7)");
    }

    #[test]
    fn changed_faces_fall_back_to_a_new_file_with_a_warning() {
        let loaded = read("o x\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nf 1/1 2/1 3/1\n").unwrap();
        let mut changed = loaded.mesh.clone();
        changed.polygons = Polygons::from_triangles(&[[1, 3, 2]]);
        changed.triangles = vec![[1, 3, 2]];
        let (out, warnings) = write(&changed, &loaded.attributes);
        assert!(out.starts_with("# written by shapeup") && out.ends_with("f 2 4 3\n"), "{out}");
        assert_eq!(warnings.count("obj_lines_not_kept"), 1);
        // The texture coordinates belonged to the old faces; both they and the groups are dropped.
        assert_eq!(warnings.count("attributes_dropped"), 2, "{warnings:?}");
    }
}
