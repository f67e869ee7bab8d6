//! Stanford PLY: ascii, binary little endian and binary big endian, kept whole.
//!
//! **Read.** The header (`format`, `comment`, `obj_info`, `element NAME COUNT`,
//! `property TYPE NAME`, `property list COUNT_TYPE ITEM_TYPE NAME`, with the types
//! `char uchar short ushort int uint float double` or `int8 … float64`) and every element with
//! every property are kept in [`PlyAttributes`] (the mesh's [`Attributes::Ply`](super::Attributes::Ply)): the header
//! lines verbatim and in order, each property's declared type and its values, exactly (every
//! PLY type converts exactly to `f64`; an ascii value is read as its declared type holds it, so
//! an ascii file and a binary one with the same header hold the same values). The mesh is built
//! from the `vertex` element's scalar `x y z` (vertices in file order, also those no face uses),
//! one polygon per instance of the `face` element's list `vertex_indices` (or `vertex_index`),
//! then the triangles of a `tristrips` element's list `vertex_indices`: −1 restarts a strip,
//! every other triangle is flipped so that all turn the same way (OpenGL's order), and a
//! triangle that repeats a vertex (strips use them to join) is skipped and counted. In ascii,
//! each element instance is one line. A file must start with `ply`; an ascii one saved as UTF-16
//! (byte-order mark `FF FE` or `FE FF`) is decoded, a binary one cannot be UTF-16 text and is
//! refused naming the encoding.
//!
//! **Hostile sizes.** Header counts reserve at most [`MAX_PREALLOCATION`](super::MAX_PREALLOCATION) values in all, however
//! many elements and properties the header declares; the rest grows as data actually arrives, and
//! every instance, list item and strip index is read (and checked) once, so a file of a few KB
//! that claims 2³¹ elements or lists of 4·10⁹ items fails at its end, in time and memory
//! proportional to its size, and a face of any number of corners reads in linear time. Text
//! quoted in errors (names, values, header lines) is cut to 60 characters.
//!
//! **Written** ([`write_ply`]), a mesh read from PLY gets its header back line for line (only
//! `format` changes when the encoding does) and every element and property with its type; only
//! `x y z` (the mesh's positions, in their declared type) and, when the vertices have
//! `nx ny nz`, the normals (recomputed, angle-weighted per vertex) change. Any other mesh gets
//! `double` x y z, `float` nx ny nz, `uchar` red green blue, faces as
//! `list uchar int vertex_indices` and MeshLab's per-corner `list uchar float texcoord`, as far
//! as its attributes have them; the rest is reported.
//!
//! Hand-written rather than `ply-rs-bw`, to report where a file is malformed (the line, or the
//! byte offset and element index) and to bound what header counts allocate.

mod attributes;
mod header;
mod read;
mod scalar;
mod write;

pub use attributes::{PlyAttributes, PlyElement, PlyProperty, PlyType};
pub use read::read_ply;
pub use scalar::{PlyEncoding, PlyScalar};
pub use write::write_ply;
