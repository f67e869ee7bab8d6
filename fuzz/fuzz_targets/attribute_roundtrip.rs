//! The attribute round trip: read an OBJ, PLY or OFF file, write it with the same format's
//! writer, read that again. The second read must succeed and equal the first bit for bit in
//! positions, polygons and attributes (normals aside: writers recompute them), and a second
//! round trip must reproduce the first's bytes (a fixed point).
//!
//! The first input byte picks the format (`b % 3`: OBJ, PLY, OFF) and, for PLY, the encoding
//! written (`b / 3 % 4`: the file's own, ascii, binary little endian, binary big endian); the
//! rest is the file.
#![no_main]

use libfuzzer_sys::fuzz_target;
use shapeup_core::Mesh;
use shapeup_core::io::{Attributes, IoError, LoadedMesh, PlyEncoding, obj, off, ply};
use shapeup_core::warnings::Warnings;
use shapeup_fuzz::path;

#[derive(Clone, Copy, Debug)]
enum Format {
    Obj,
    Ply(Option<PlyEncoding>),
    Off,
}

impl Format {
    fn of(byte: u8) -> Self {
        match byte % 3 {
            0 => Format::Obj,
            1 => Format::Ply(match byte / 3 % 4 {
                0 => None,
                1 => Some(PlyEncoding::Ascii),
                2 => Some(PlyEncoding::BinaryLittleEndian),
                _ => Some(PlyEncoding::BinaryBigEndian),
            }),
            _ => Format::Off,
        }
    }

    fn read(self, bytes: &[u8]) -> Result<LoadedMesh, IoError> {
        match self {
            Format::Obj => obj::read_obj(bytes, path("fuzz.obj")),
            Format::Ply(_) => ply::read_ply(bytes, path("fuzz.ply")),
            Format::Off => off::read_off(bytes, path("fuzz.off")),
        }
    }

    fn write(self, loaded: &LoadedMesh) -> Vec<u8> {
        let (mesh, attributes) = (&loaded.mesh, &loaded.attributes);
        let mut out = Vec::new();
        let mut warnings = Warnings::new();
        let written = match self {
            Format::Obj => obj::write_obj(&mut out, mesh, attributes, &mut warnings),
            Format::Ply(encoding) => ply::write_ply(&mut out, mesh, attributes, encoding, &mut warnings),
            Format::Off => off::write_off(&mut out, mesh, attributes, &mut warnings),
        };
        if let Err(e) = written {
            panic!("{self:?}: writing a mesh just read failed: {e}");
        }
        out
    }
}

/// Bit-exact equality through `Debug` (f64's shortest round-trip form; NaN equals NaN, -0 ≠ 0).
fn same<T: std::fmt::Debug>(a: &T, b: &T) -> bool {
    format!("{a:?}") == format!("{b:?}")
}

macro_rules! check {
    ($what:expr, $a:expr, $b:expr) => {
        if !same(&$a, &$b) {
            panic!("round trip changed {}:\n first: {:?}\nsecond: {:?}", $what, $a, $b);
        }
    };
}

/// The attributes as a written file holds them: OFF writers drop comment lines, and a plain
/// `OFF` without them carries no attributes.
fn without_comments(attributes: &Attributes) -> Attributes {
    match attributes.clone().with_comments(0) {
        Attributes::Off(a)
            if a.keyword == "OFF"
                && a.vertex_extra.iter().all(String::is_empty)
                && a.face_extra.iter().all(String::is_empty) =>
        {
            Attributes::None
        }
        other => other,
    }
}

/// The first read against the second: everything but the normals' values.
fn compare(format: Format, a: &LoadedMesh, b: &LoadedMesh) {
    let (x, y) = (&without_comments(&a.attributes), &without_comments(&b.attributes));
    let (a, b) = (&a.mesh, &b.mesh);
    let bits = |m: &Mesh| m.positions.iter().map(|p| p.to_array().map(f64::to_bits)).collect::<Vec<_>>();
    check!("positions", bits(a), bits(b));
    check!("polygons", a.polygons, b.polygons);
    check!("triangles", a.triangles, b.triangles);
    check!("triangle_polygon", a.triangle_polygon, b.triangle_polygon);
    check!("tetrahedra", a.tetrahedra, b.tetrahedra);
    check!("texture coordinates", x.texcoords(&a.polygons), y.texcoords(&b.polygons));
    check!("vertex colours", x.vertex_colors(), y.vertex_colors());
    check!("attribute kinds", x.kinds(), y.kinds());
    check!("has_normals", x.has_normals(), y.has_normals());
    check!("vertex scalars", x.vertex_scalars(), y.vertex_scalars());
    match (x, y) {
        (Attributes::None, Attributes::None) => {}
        (Attributes::Obj(x), Attributes::Obj(y)) => {
            check!("vt", x.texcoords, y.texcoords);
            check!("corner vt indices", x.corner_texcoords, y.corner_texcoords);
            check!("corner vn indices", x.corner_normals, y.corner_normals);
            check!("vn count", x.normals.len(), y.normals.len());
            check!("colours", x.colors, y.colors);
            check!(
                "crlf, final newline, BOM, groups, faces",
                (x.crlf, x.final_newline, x.bom, x.groups_and_materials, x.faces),
                (y.crlf, y.final_newline, y.bom, y.groups_and_materials, y.faces)
            );
            check!("line count", x.lines.len(), y.lines.len());
            for (i, (p, q)) in x.lines.iter().zip(&y.lines).enumerate() {
                let normal = matches!((p, q), (obj::ObjLine::Normal { .. }, obj::ObjLine::Normal { .. }));
                if !normal {
                    check!(format!("line {}", i + 1), p, q);
                }
            }
        }
        (Attributes::Ply(x), Attributes::Ply(y)) => {
            if matches!(format, Format::Ply(None)) {
                check!("encoding", x.encoding(), y.encoding());
                check!("header", x.header_lines(), y.header_lines());
            } else {
                // The format line's keyword may be followed by any whitespace (a tab too).
                let no_format = |h: &[String]| {
                    h.iter().filter(|l| l.split_whitespace().next() != Some("format")).cloned().collect::<Vec<_>>()
                };
                check!("header", no_format(x.header_lines()), no_format(y.header_lines()));
            }
            check!("element count", x.elements().len(), y.elements().len());
            for (e, f) in x.elements().iter().zip(y.elements()) {
                check!(
                    "element",
                    (e.name(), e.count(), e.properties().len()),
                    (f.name(), f.count(), f.properties().len())
                );
                for (p, q) in e.properties().iter().zip(f.properties()) {
                    check!(format!("element {} property", e.name()), (p.name(), p.ty()), (q.name(), q.ty()));
                    let normal = e.name() == "vertex" && ["nx", "ny", "nz"].contains(&p.name());
                    if !normal {
                        let what = format!("element {} property {}", e.name(), p.name());
                        check!(what, (p.values(), p.offsets()), (q.values(), q.offsets()));
                    }
                }
            }
        }
        (Attributes::Off(x), Attributes::Off(y)) => {
            check!("keyword, layout", (&x.keyword, x.layout), (&y.keyword, y.layout));
            check!("face values", x.face_extra, y.face_extra);
            // `N` layouts: the first three values after x y z are the recomputed normal.
            let skip = if x.layout.normal { 3 } else { 0 };
            let rest = |v: &[String]| {
                v.iter().map(|s| s.split(' ').skip(skip).collect::<Vec<_>>().join(" ")).collect::<Vec<_>>()
            };
            check!("vertex values", rest(&x.vertex_extra), rest(&y.vertex_extra));
        }
        _ => panic!("round trip changed the kind of attributes:\n first: {x:?}\nsecond: {y:?}"),
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&selector, file)) = data.split_first() else { return };
    let format = Format::of(selector);
    // Errors on the first read are the reader targets' business.
    let first = match format.read(file) {
        Ok(loaded) => loaded,
        Err(e) if shapeup_fuzz::expect_valid() => panic!("SHAPEUP_FUZZ_EXPECT_VALID: this input does not read: {e}"),
        Err(_) => return,
    };
    let written = format.write(&first);
    let second = match format.read(&written) {
        Ok(loaded) => loaded,
        Err(e) => {
            panic!("{format:?}: the writer's output does not read back: {e}\n{}", String::from_utf8_lossy(&written))
        }
    };
    compare(format, &first, &second);
    let rewritten = format.write(&second);
    if rewritten != written {
        panic!(
            "{format:?}: a second round trip writes other bytes:\n first: {:?}\nsecond: {:?}",
            String::from_utf8_lossy(&written),
            String::from_utf8_lossy(&rewritten)
        );
    }
    let Ok(third) = format.read(&rewritten) else { panic!("{format:?}: the second write does not read back") };
    check!("the mesh after a second round trip", (&second.mesh, &second.attributes), (&third.mesh, &third.attributes));
});
