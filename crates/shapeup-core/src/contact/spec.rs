//! The one description of a collider and of the `[contact]` settings, as scenes, the command
//! line, the editor and Python give them (input frame, input units), and how they become a
//! [`ContactModel`](super::ContactModel) in the working frame.

use super::collider::{Collider, Motion};
use super::shape::{MeshShape, Shape, rotation};
use crate::geometry::WorkingFrame;
use crate::motion::{Rotate, Spin};
use crate::text::number;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};
use std::path::PathBuf;

/// Mean edge length × this is the default [`ContactSettings::thickness`]: thin enough that
/// neighbouring vertices of a surface at rest never count as touching, thick enough to be
/// kept with a few iterations per step.
pub const DEFAULT_THICKNESS_FRACTION: f64 = 0.25;

/// Mean edge length × this is the largest self-collision thickness. Beyond it every vertex
/// starts within the thickness of the triangles two rings away: the rest shape is all contact
/// (millions of pairs on a 61×61 cloth at 6 edge lengths) and pushes itself apart.
pub const MAX_SELF_THICKNESS_FRACTION: f64 = 1.0;

/// The rest shape's bounding-box diagonal × this is the largest contact thickness given. A
/// 1 m cloth over a box with a thickness of 5 m was pushed 5 m out at once and thrown at
/// 300 m/s.
pub const MAX_THICKNESS_OF_SIZE: f64 = 0.25;

/// The `[contact]` table.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ContactSettings {
    /// Whether the surface collides with itself (default false).
    pub self_collision: bool,
    /// Distance kept from colliders and between parts of the surface (input units ≥ 0;
    /// default [`DEFAULT_THICKNESS_FRACTION`] × the mean edge length). Left out for the
    /// default; a null (a JSON null, a TOML nan) is refused, not taken for it.
    #[serde(deserialize_with = "a_number")]
    pub thickness: Option<f64>,
    /// Coulomb μ ≥ 0 of self contact (default 0).
    pub friction: f64,
}

/// An optional number that, when given, is a number (not null).
fn a_number<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    f64::deserialize(d).map(Some)
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings { self_collision: false, thickness: None, friction: 0.0 }
    }
}

impl ContactSettings {
    /// Checks the values, naming the first bad one.
    ///
    /// # Errors
    /// A thickness or friction that is negative or not finite.
    pub fn validate(&self) -> Result<(), ColliderError> {
        if let Some(t) = self.thickness
            && !(t.is_finite() && (0.0..=MAX_MAGNITUDE).contains(&t))
        {
            return Err(ColliderError::Invalid(format!(
                "thickness must be a finite number in [0, 1e12], found {}",
                number(t)
            )));
        }
        if !(self.friction.is_finite() && (0.0..=MAX_MAGNITUDE).contains(&self.friction)) {
            return Err(ColliderError::Invalid(format!(
                "friction must be a finite number in [0, 1e12], found {}",
                number(self.friction)
            )));
        }
        Ok(())
    }

    /// The thickness in working units: `thickness` (input units) × `scale`, else
    /// [`DEFAULT_THICKNESS_FRACTION`] × `mean_edge_length` (working units); `size` is the rest
    /// shape's bounding-box diagonal (working units).
    ///
    /// # Errors
    /// A thickness over [`MAX_THICKNESS_OF_SIZE`] × `size` (a skin that wide would hold the
    /// surface a large part of its own size from every collider, and turn the push out into
    /// speed); with `self_collision`, one over [`MAX_SELF_THICKNESS_FRACTION`] × the mean edge
    /// length. Each named with both numbers in input units.
    pub fn resolve_thickness(&self, scale: f64, mean_edge_length: f64, size: f64) -> Result<f64, ColliderError> {
        let thickness = match self.thickness {
            Some(t) => t * scale,
            None => DEFAULT_THICKNESS_FRACTION * mean_edge_length,
        };
        let limit = MAX_SELF_THICKNESS_FRACTION * mean_edge_length;
        if self.self_collision && thickness > limit {
            return Err(ColliderError::Invalid(format!(
                "thickness {} is over the mean edge length {} (input units): with self_collision every vertex \
                 would start in contact with its neighbours' triangles; give at most the mean edge length (default \
                 {DEFAULT_THICKNESS_FRACTION} of it), or refine the mesh",
                number(thickness / scale),
                number(limit / scale)
            )));
        }
        let most = MAX_THICKNESS_OF_SIZE * size;
        if self.thickness.is_some() && thickness > most {
            return Err(ColliderError::Invalid(format!(
                "thickness {} is over {MAX_THICKNESS_OF_SIZE} of the mesh's size (its bounding-box diagonal {}, input \
                 units): the thickness is a skin around the surface (default {DEFAULT_THICKNESS_FRACTION} of the mean \
                 edge length, {})",
                number(thickness / scale),
                number(size / scale),
                number(DEFAULT_THICKNESS_FRACTION * mean_edge_length / scale)
            )));
        }
        Ok(thickness)
    }
}

/// A collider's shape as given (input frame).
#[derive(Debug, Clone, PartialEq)]
pub enum ShapeSpec {
    /// `type = "plane"`: the half-space below the plane through `point` with `normal`.
    Plane {
        /// A point on the plane.
        point: [f64; 3],
        /// Outward normal (non-zero).
        normal: [f64; 3],
    },
    /// `type = "sphere"`.
    Sphere {
        /// Centre.
        center: [f64; 3],
        /// Radius > 0.
        radius: f64,
    },
    /// `type = "capsule"`: the points within `radius` of the segment ab.
    Capsule {
        /// One end.
        a: [f64; 3],
        /// The other end (≠ a).
        b: [f64; 3],
        /// Radius > 0.
        radius: f64,
    },
    /// `type = "box"`: the axis-aligned box [min, max], optionally turned.
    Box {
        /// Lowest corner.
        min: [f64; 3],
        /// Highest corner (≥ min).
        max: [f64; 3],
        /// A rotation as position groups take (centre default: the box's centre).
        rotate: Option<Rotate>,
    },
    /// `type = "mesh"`: any mesh file shapeup reads, relative to the scene file.
    Mesh {
        /// The file.
        path: PathBuf,
        /// Whether it is closed (default: closed when every edge has two triangles).
        closed: Option<bool>,
        /// An open mesh's thickness behind its front (input units ≥ 0; default the contact
        /// thickness).
        thickness: Option<f64>,
        /// Where the file's mesh is placed: p ↦ c + R (p − c) + translate, R the `rotate`
        /// about its centre c (file coordinates; default the file's origin), as a DCC tool
        /// places an object about its origin. Default: where the file puts it.
        translate: [f64; 3],
        /// See `translate`.
        rotate: Option<Rotate>,
    },
}

/// One `[[colliders]]` entry.
#[derive(Debug, Clone, PartialEq)]
pub struct ColliderSpec {
    /// The shape.
    pub shape: ShapeSpec,
    /// Coulomb μ ≥ 0 (default 0).
    pub friction: f64,
    /// Velocity (input units per second; default 0).
    pub velocity: [f64; 3],
    /// A constant spin (centre default: the shape's centre).
    pub spin: Option<Spin>,
}

/// Why a collider or the contact settings are refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ColliderError {
    /// A value out of range, a missing or unknown key.
    #[error("{0}")]
    Invalid(String),
    /// The mesh file could not be read or used.
    #[error("{path}: {message}")]
    Mesh {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

/// The keys every collider takes besides its shape's.
const COMMON_KEYS: [&str; 4] = ["type", "friction", "velocity", "spin"];

/// The collider types and their own keys.
pub const COLLIDER_TYPES: [(&str, &[&str]); 5] = [
    ("plane", &["point", "normal"]),
    ("sphere", &["center", "radius"]),
    ("capsule", &["a", "b", "radius"]),
    ("box", &["min", "max", "rotate"]),
    ("mesh", &["path", "closed", "thickness", "translate", "rotate"]),
];

/// A mesh collider's placement as a map of file coordinates to the scene's: p ↦ c + R (p − c)
/// + translate (see [`ShapeSpec::Mesh`]).
pub fn mesh_placement(translate: [f64; 3], rotate: Option<&Rotate>) -> impl Fn(DVec3) -> DVec3 {
    let (turn, center) = match rotate {
        Some(r) => (rotation(direction(r.axis), r.angle_deg), r.center.map_or(DVec3::ZERO, DVec3::from)),
        None => (glam::DQuat::IDENTITY, DVec3::ZERO),
    };
    let shift = DVec3::from(translate);
    move |p| center + turn * (p - center) + shift
}

/// Checks a turn table's values (`rotate`: `angle_deg`; `spin`: `deg_per_s`): a non-zero
/// finite axis, a finite amount within ±1e12, a finite centre.
fn check_turn(
    table: &str,
    axis: [f64; 3],
    amount_key: &str,
    amount: f64,
    center: Option<[f64; 3]>,
) -> Result<(), ColliderError> {
    check_direction(&format!("{table}.axis"), finite3(&format!("{table}.axis"), axis)?)?;
    if !(amount.is_finite() && amount.abs() <= MAX_MAGNITUDE) {
        return Err(invalid(format!("`{table}.{amount_key}` must be a finite number within ±1e12")));
    }
    if let Some(c) = center {
        finite3(&format!("{table}.center"), c)?;
    }
    Ok(())
}

/// Checks a `rotate` table's values.
fn check_rotate(r: &Rotate) -> Result<(), ColliderError> {
    check_turn("rotate", r.axis, "angle_deg", r.angle_deg, r.center)
}

fn invalid(message: impl Into<String>) -> ColliderError {
    ColliderError::Invalid(message.into())
}

fn take<T: serde::de::DeserializeOwned>(entry: &mut Map<String, Value>, key: &str) -> Result<Option<T>, ColliderError> {
    match entry.remove(key) {
        None => Ok(None),
        // A TOML scene's nan or inf arrives as null (JSON has no such numbers), as does a JSON
        // scene's own null.
        Some(v) if contains_null(&v) => {
            Err(invalid(format!("`{key}` must hold finite numbers only (not nan, inf or null)")))
        }
        Some(v) => crate::text::value_as(v).map(Some).map_err(|e| invalid(format!("`{key}`: {e}"))),
    }
}

/// `value` without its null members (an unset optional `center`), as a scene leaves them out.
fn without_nulls(value: Value) -> Value {
    match value {
        Value::Object(map) => Value::Object(map.into_iter().filter(|(_, v)| !v.is_null()).collect()),
        other => other,
    }
}

fn contains_null(v: &Value) -> bool {
    match v {
        Value::Null => true,
        Value::Array(items) => items.iter().any(contains_null),
        Value::Object(map) => map.values().any(contains_null),
        _ => false,
    }
}

/// The largest magnitude a collider's coordinate, length, speed or rate may have: beyond it
/// the closest-point arithmetic loses every digit of a shape of ordinary size (a box from
/// −1e300 to 1e300 has no top).
pub const MAX_MAGNITUDE: f64 = 1e12;

fn required<T: serde::de::DeserializeOwned>(
    entry: &mut Map<String, Value>,
    key: &str,
    kind: &str,
) -> Result<T, ColliderError> {
    take(entry, key)?.ok_or_else(|| invalid(format!("a {kind} collider needs `{key}`")))
}

fn finite3(key: &str, v: [f64; 3]) -> Result<DVec3, ColliderError> {
    let d = DVec3::from(v);
    if !d.is_finite() {
        return Err(invalid(format!("`{key}` must be three finite numbers")));
    }
    if d.abs().max_element() > MAX_MAGNITUDE {
        return Err(invalid(format!("`{key}` is too large: each number must be within ±{MAX_MAGNITUDE:e}")));
    }
    Ok(d)
}

fn positive(key: &str, v: f64) -> Result<f64, ColliderError> {
    if !(v.is_finite() && v > 0.0) {
        return Err(invalid(format!("`{key}` must be a finite number > 0, found {}", number(v))));
    }
    if v > MAX_MAGNITUDE {
        return Err(invalid(format!("`{key}` is too large: at most {MAX_MAGNITUDE:e}, found {}", number(v))));
    }
    Ok(v)
}

/// The shortest vector [`check_direction`] takes as a direction: its length squared is still a
/// normal number (1e-300 squared is 0).
const MIN_DIRECTION_LENGTH: f64 = 1e-150;

/// The length of `d` without underflow or overflow (its largest component first).
fn scaled_length(d: DVec3) -> f64 {
    let m = d.abs().max_element();
    if m == 0.0 { 0.0 } else { m * (d / m).length() }
}

/// Checks a plane's normal or a turn's axis: zero is refused as zero; a length under
/// [`MIN_DIRECTION_LENGTH`] as too small to give a direction (its length squared underflows).
fn check_direction(key: &str, d: DVec3) -> Result<(), ColliderError> {
    let length = scaled_length(d);
    if length == 0.0 {
        return Err(invalid(format!("`{key}` must be non-zero")));
    }
    if length < MIN_DIRECTION_LENGTH {
        return Err(invalid(format!(
            "`{key}` is too small to give a direction: its length is {}, under {}",
            number(length),
            number(MIN_DIRECTION_LENGTH)
        )));
    }
    Ok(())
}

/// A direction scaled to unit length without overflowing (its largest component first).
fn direction(v: [f64; 3]) -> DVec3 {
    let d = DVec3::from(v);
    (d / d.abs().max_element()).normalize()
}

impl ColliderSpec {
    /// Reads one entry (a scene's table, the editor's or Python's dictionary), checking every
    /// key and value.
    ///
    /// # Errors
    /// [`ColliderError::Invalid`] naming the key: an unknown type or key, a missing key, a
    /// negative radius or μ, a normal or capsule axis that is zero or too short to give a
    /// direction, a box with min > max.
    pub fn from_entry(mut entry: Map<String, Value>) -> Result<ColliderSpec, ColliderError> {
        let kind: String =
            take(&mut entry, "type")?.ok_or_else(|| invalid("missing `type` (plane, sphere, capsule, box or mesh)"))?;
        let Some((_, keys)) = COLLIDER_TYPES.iter().find(|(name, _)| *name == kind) else {
            return Err(invalid(format!("unknown collider type \"{kind}\" (plane, sphere, capsule, box or mesh)")));
        };
        if let Some(key) = entry.keys().find(|k| !COMMON_KEYS.contains(&k.as_str()) && !keys.contains(&k.as_str())) {
            return Err(invalid(format!(
                "unknown key `{key}` for a {kind} collider (it takes {}, friction, velocity, spin)",
                keys.join(", ")
            )));
        }
        let shape = match kind.as_str() {
            "plane" => ShapeSpec::Plane {
                point: required(&mut entry, "point", &kind)?,
                normal: required(&mut entry, "normal", &kind)?,
            },
            "sphere" => ShapeSpec::Sphere {
                center: required(&mut entry, "center", &kind)?,
                radius: required(&mut entry, "radius", &kind)?,
            },
            "capsule" => ShapeSpec::Capsule {
                a: required(&mut entry, "a", &kind)?,
                b: required(&mut entry, "b", &kind)?,
                radius: required(&mut entry, "radius", &kind)?,
            },
            "box" => ShapeSpec::Box {
                min: required(&mut entry, "min", &kind)?,
                max: required(&mut entry, "max", &kind)?,
                rotate: take(&mut entry, "rotate")?,
            },
            _ => ShapeSpec::Mesh {
                path: required(&mut entry, "path", &kind)?,
                closed: take(&mut entry, "closed")?,
                thickness: take(&mut entry, "thickness")?,
                translate: take(&mut entry, "translate")?.unwrap_or([0.0; 3]),
                rotate: take(&mut entry, "rotate")?,
            },
        };
        let spec = ColliderSpec {
            shape,
            friction: take(&mut entry, "friction")?.unwrap_or(0.0),
            velocity: take(&mut entry, "velocity")?.unwrap_or([0.0; 3]),
            spin: take(&mut entry, "spin")?,
        };
        spec.validate()?;
        Ok(spec)
    }

    /// The entry [`ColliderSpec::from_entry`] reads back (what a scene file writes).
    pub fn to_entry(&self) -> Map<String, Value> {
        let mut m = Map::new();
        let mut put = |k: &str, v: Value| {
            m.insert(k.into(), v);
        };
        match &self.shape {
            ShapeSpec::Plane { point, normal } => {
                put("type", "plane".into());
                put("point", serde_json::json!(point));
                put("normal", serde_json::json!(normal));
            }
            ShapeSpec::Sphere { center, radius } => {
                put("type", "sphere".into());
                put("center", serde_json::json!(center));
                put("radius", serde_json::json!(radius));
            }
            ShapeSpec::Capsule { a, b, radius } => {
                put("type", "capsule".into());
                put("a", serde_json::json!(a));
                put("b", serde_json::json!(b));
                put("radius", serde_json::json!(radius));
            }
            ShapeSpec::Box { min, max, rotate } => {
                put("type", "box".into());
                put("min", serde_json::json!(min));
                put("max", serde_json::json!(max));
                if let Some(r) = rotate {
                    put("rotate", without_nulls(serde_json::json!(r)));
                }
            }
            ShapeSpec::Mesh { path, closed, thickness, translate, rotate } => {
                put("type", "mesh".into());
                put("path", serde_json::json!(path));
                if let Some(c) = closed {
                    put("closed", serde_json::json!(c));
                }
                if let Some(t) = thickness {
                    put("thickness", serde_json::json!(t));
                }
                if *translate != [0.0; 3] {
                    put("translate", serde_json::json!(translate));
                }
                if let Some(r) = rotate {
                    put("rotate", without_nulls(serde_json::json!(r)));
                }
            }
        }
        if self.friction != 0.0 {
            put("friction", serde_json::json!(self.friction));
        }
        if self.velocity != [0.0; 3] {
            put("velocity", serde_json::json!(self.velocity));
        }
        if let Some(s) = &self.spin {
            put("spin", without_nulls(serde_json::json!(s)));
        }
        m
    }

    /// The type's name (`"sphere"`, …).
    pub fn kind(&self) -> &'static str {
        match self.shape {
            ShapeSpec::Plane { .. } => "plane",
            ShapeSpec::Sphere { .. } => "sphere",
            ShapeSpec::Capsule { .. } => "capsule",
            ShapeSpec::Box { .. } => "box",
            ShapeSpec::Mesh { .. } => "mesh",
        }
    }

    /// Checks every value (not the mesh file, which [`ColliderSpec::build`] reads).
    ///
    /// # Errors
    /// [`ColliderError::Invalid`] naming the key.
    pub fn validate(&self) -> Result<(), ColliderError> {
        match &self.shape {
            ShapeSpec::Plane { point, normal } => {
                finite3("point", *point)?;
                check_direction("normal", finite3("normal", *normal)?)?;
            }
            ShapeSpec::Sphere { center, radius } => {
                finite3("center", *center)?;
                positive("radius", *radius)?;
            }
            ShapeSpec::Capsule { a, b, radius } => {
                let (a, b) = (finite3("a", *a)?, finite3("b", *b)?);
                let axis = b - a;
                if axis == DVec3::ZERO {
                    return Err(invalid("the capsule's axis is zero: `a` and `b` must differ"));
                }
                // Closest points divide by the axis's length squared, which underflows.
                if scaled_length(axis) < MIN_DIRECTION_LENGTH {
                    return Err(invalid(format!(
                        "the capsule's axis is too short to give a direction: `a` and `b` are {} apart, under {}",
                        number(scaled_length(axis)),
                        number(MIN_DIRECTION_LENGTH)
                    )));
                }
                positive("radius", *radius)?;
            }
            ShapeSpec::Box { min, max, rotate } => {
                let (lo, hi) = (finite3("min", *min)?, finite3("max", *max)?);
                if let Some(k) = (0..3).find(|&k| lo[k] > hi[k]) {
                    return Err(invalid(format!("`min` > `max` along {} ({} > {})", ["x", "y", "z"][k], lo[k], hi[k])));
                }
                if let Some(r) = rotate {
                    check_rotate(r)?;
                }
            }
            ShapeSpec::Mesh { path, thickness, translate, rotate, .. } => {
                finite3("translate", *translate)?;
                if let Some(r) = rotate {
                    check_rotate(r)?;
                }
                if path.as_os_str().is_empty() {
                    return Err(invalid("`path` is empty"));
                }
                if let Some(t) = thickness
                    && !(t.is_finite() && (0.0..=MAX_MAGNITUDE).contains(t))
                {
                    return Err(invalid(format!(
                        "`thickness` must be a finite number in [0, 1e12], found {}",
                        number(*t)
                    )));
                }
            }
        }
        if !(self.friction.is_finite() && (0.0..=MAX_MAGNITUDE).contains(&self.friction)) {
            return Err(invalid(format!(
                "`friction` must be a finite number in [0, 1e12], found {}",
                number(self.friction)
            )));
        }
        finite3("velocity", self.velocity)?;
        if let Some(s) = &self.spin {
            check_turn("spin", s.axis, "deg_per_s", s.deg_per_s, s.center)?;
        }
        Ok(())
    }

    /// The collider in the working `frame`; a mesh is read from `base_dir` / path. `thickness`
    /// is the contact thickness (working units), an open mesh's default.
    ///
    /// # Errors
    /// [`ColliderError::Mesh`] for a mesh that cannot be read, has no faces or is said to be
    /// closed while open.
    pub fn build(
        &self,
        frame: &WorkingFrame,
        base_dir: &std::path::Path,
        thickness: f64,
    ) -> Result<Collider, ColliderError> {
        self.validate()?;
        let point = |p: [f64; 3]| frame.to_working(DVec3::from(p));
        let length = |l: f64| l * frame.scale;
        let (shape, center) = match &self.shape {
            ShapeSpec::Plane { point: p, normal } => {
                let normal = direction(*normal);
                (Shape::Plane { point: point(*p), normal }, point(*p))
            }
            ShapeSpec::Sphere { center, radius } => {
                (Shape::Sphere { center: point(*center), radius: length(*radius) }, point(*center))
            }
            ShapeSpec::Capsule { a, b, radius } => {
                let (a, b) = (point(*a), point(*b));
                (Shape::Capsule { a, b, radius: length(*radius) }, 0.5 * (a + b))
            }
            ShapeSpec::Box { min, max, rotate } => {
                let (lo, hi) = (DVec3::from(*min), DVec3::from(*max));
                let mut center = 0.5 * (lo + hi);
                let mut turn = glam::DQuat::IDENTITY;
                if let Some(r) = rotate {
                    turn = rotation(direction(r.axis), r.angle_deg);
                    let pivot = r.center.map_or(center, DVec3::from);
                    center = pivot + turn * (center - pivot);
                }
                let center = frame.to_working(center);
                (Shape::Box { center, half: 0.5 * (hi - lo) * frame.scale, rotation: turn }, center)
            }
            ShapeSpec::Mesh { path, closed, thickness: own, translate, rotate } => {
                let file = base_dir.join(path);
                let fail = |message: String| ColliderError::Mesh { path: file.clone(), message };
                // The reader's error names the file itself.
                let loaded = crate::io::read_mesh(&file).map_err(|e| ColliderError::Invalid(e.to_string()))?;
                let mesh = loaded.mesh;
                if mesh.triangles.is_empty() {
                    return Err(fail(format!("has no faces{}", mesh.why_no_triangles())));
                }
                // As every scene number: beyond ±1e12 the distance queries lose all precision.
                if let Some((v, p)) = mesh
                    .positions
                    .iter()
                    .enumerate()
                    .find(|(_, p)| !(p.is_finite() && p.abs().max_element() <= MAX_MAGNITUDE))
                {
                    return Err(fail(format!(
                        "vertex {v} (from 0) is at ({}, {}, {}): coordinates must be finite numbers within ±1e12",
                        number(p.x),
                        number(p.y),
                        number(p.z)
                    )));
                }
                let is_closed = every_edge_twice(&mesh.triangles);
                if *closed == Some(true) && !is_closed {
                    return Err(fail(
                        "is used as closed (closed = true) but is open: some edges have one triangle; drop `closed` to use it one-sided"
                            .into(),
                    ));
                }
                let place = mesh_placement(*translate, rotate.as_ref());
                let positions: Vec<DVec3> = mesh.positions.iter().map(|&p| frame.to_working(place(p))).collect();
                let centroid = positions.iter().copied().sum::<DVec3>() / positions.len().max(1) as f64;
                let use_closed = closed.unwrap_or(is_closed);
                if use_closed && let Some(defect) = closed_mesh_defect(&positions, &mesh.triangles) {
                    return Err(fail(defect));
                }
                let behind = own.map_or(thickness, length);
                let shape =
                    MeshShape::new(&positions, &mesh.triangles, use_closed, behind).map_err(|e| fail(e.to_string()))?;
                (Shape::Mesh(Box::new(shape)), centroid)
            }
        };
        let spin = self.spin.map(|s| {
            let axis = direction(s.axis);
            let c = s.center.map_or(center, point);
            (axis, c, s.deg_per_s.to_radians())
        });
        Ok(Collider {
            shape,
            friction: self.friction,
            motion: Motion { velocity: DVec3::from(self.velocity) * frame.scale, spin },
        })
    }
}

/// Why a closed mesh cannot tell inside from outside, if it cannot: two triangles that run
/// along a shared edge the same way (faces not consistently oriented: the inside flips from
/// face to face), or a signed volume V = Σ (a − o) · ((b − o) × (c − o)) / 6 that is not
/// positive (faces pointing inward, or nothing enclosed, as a two-sided sheet). Either made
/// the surface pull in cloth far from it.
fn closed_mesh_defect(positions: &[DVec3], triangles: &[[u32; 3]]) -> Option<String> {
    let mut directed: Vec<(u32, u32, usize)> =
        triangles.iter().enumerate().flat_map(|(t, tri)| (0..3).map(move |k| (tri[k], tri[(k + 1) % 3], t))).collect();
    directed.sort_unstable();
    if let Some(w) = directed.windows(2).find(|w| (w[0].0, w[0].1) == (w[1].0, w[1].1)) {
        return Some(format!(
            "is closed but its faces are not consistently oriented: triangles {} and {} (from 0) both run from vertex {} to {}; \
             orient them consistently (Blender: Mesh > Normals > Recalculate Outside) or set closed = false to use it one-sided",
            w[0].2, w[1].2, w[0].0, w[0].1
        ));
    }
    let corner = |v: u32| positions.get(v as usize).copied().unwrap_or(DVec3::ZERO);
    let origin = positions.iter().copied().sum::<DVec3>() / positions.len().max(1) as f64;
    let volume = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| corner(v) - origin);
            a.dot(b.cross(c))
        })
        .sum::<f64>()
        / 6.0;
    let size = crate::geometry::points_diagonal(positions);
    if volume < 0.0 && -volume > 1e-9 * size.powi(3) {
        Some(format!(
            "is closed but its faces point inward (signed volume {volume:.3e}): flip them (Blender: Mesh > Normals > Flip)"
        ))
    } else if volume <= 1e-9 * size.powi(3) {
        Some(format!(
            "is closed but encloses no volume (signed volume {volume:.3e}, bounding-box diagonal {size:.3e}): \
             use a box collider, or set closed = false to use it one-sided"
        ))
    } else {
        None
    }
}

/// Whether every edge of `triangles` belongs to exactly two of them (a closed surface).
fn every_edge_twice(triangles: &[[u32; 3]]) -> bool {
    crate::topology::unique_edges(triangles).1.iter().all(|&count| count == 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(json: &str) -> Map<String, Value> {
        match serde_json::from_str(json) {
            Ok(Value::Object(m)) => m,
            _ => Map::new(),
        }
    }

    #[test]
    fn the_thickness_resolves_to_the_default_fraction_and_self_collision_caps_it() {
        let (scale, edge) = (2.0, 0.1);
        let settings = |self_collision, thickness| ContactSettings { self_collision, thickness, friction: 0.0 };
        let resolved = |s: ContactSettings| s.resolve_thickness(scale, edge, 100.0);
        assert_eq!(resolved(settings(true, None)).ok(), Some(DEFAULT_THICKNESS_FRACTION * edge));
        // Input units × scale; at most the mean edge length with self-collision.
        assert_eq!(resolved(settings(true, Some(0.05))).ok(), Some(0.1));
        let err = resolved(settings(true, Some(0.051))).map(|_| ()).unwrap_err().to_string();
        assert!(err.contains("thickness 0.051 is over the mean edge length 0.05"), "{err}");
        // Colliders alone take any thickness up to a quarter of the mesh's size.
        assert_eq!(resolved(settings(false, Some(10.0))).ok(), Some(20.0));
        assert_eq!(resolved(settings(false, Some(12.5))).ok(), Some(25.0));
        let err = resolved(settings(false, Some(12.6))).map(|_| ()).unwrap_err().to_string();
        assert!(err.contains("thickness 12.6 is over 0.25 of the mesh's size (its bounding-box diagonal 50"), "{err}");
    }

    #[test]
    fn every_type_reads_and_writes_back() {
        for text in [
            r#"{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "friction": 0.3}"#,
            r#"{"type": "sphere", "center": [0, 1, 0], "radius": 0.5, "velocity": [1, 0, 0]}"#,
            r#"{"type": "capsule", "a": [0, 0, 0], "b": [1, 0, 0], "radius": 0.2}"#,
            r#"{"type": "box", "min": [0, 0, 0], "max": [1, 1, 1], "rotate": {"axis": [0, 1, 0], "angle_deg": 30}}"#,
            r#"{"type": "mesh", "path": "terrain.obj", "spin": {"axis": [0, 1, 0], "deg_per_s": 90}}"#,
            r#"{"type": "mesh", "path": "t.obj", "translate": [1, 2, 3], "rotate": {"axis": [1, 0, 0], "angle_deg": 45, "center": [0, 1, 0]}}"#,
        ] {
            let spec = ColliderSpec::from_entry(entry(text)).expect(text);
            assert_eq!(ColliderSpec::from_entry(spec.to_entry()).expect("written back"), spec, "{text}");
        }
    }

    #[test]
    fn bad_entries_name_the_key() {
        for (text, words) in [
            (r#"{"type": "cone"}"#, "unknown collider type \"cone\""),
            (r#"{"type": "sphere", "center": [0, 0, 0], "radius": -1}"#, "`radius`"),
            (r#"{"type": "sphere", "center": [0, 0, 0]}"#, "needs `radius`"),
            (r#"{"type": "sphere", "center": [0, 0, 0], "radius": 1, "radus": 2}"#, "unknown key `radus`"),
            (r#"{"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 0]}"#, "`normal` must be non-zero"),
            (r#"{"type": "capsule", "a": [1, 0, 0], "b": [1, 0, 0], "radius": 1}"#, "axis is zero"),
            // Non-zero, but too short for its length squared to be a number other than 0.
            (
                r#"{"type": "plane", "point": [0, 0, 0], "normal": [1e-300, 0, 0]}"#,
                "`normal` is too small to give a direction: its length is 1e-300, under 1e-150",
            ),
            (
                r#"{"type": "capsule", "a": [0, 0, 0], "b": [0, 1e-300, 0], "radius": 1}"#,
                "the capsule's axis is too short to give a direction: `a` and `b` are 1e-300 apart",
            ),
            (
                r#"{"type": "box", "min": [0, 0, 0], "max": [1, 1, 1], "rotate": {"axis": [0, 0, 1e-200], "angle_deg": 9}}"#,
                "`rotate.axis` is too small to give a direction",
            ),
            (r#"{"type": "box", "min": [0, 2, 0], "max": [1, 1, 1]}"#, "`min` > `max` along y"),
            (r#"{"type": "sphere", "center": [0, 0, 0], "radius": 1, "friction": -0.1}"#, "`friction`"),
            (r#"{"type": "mesh", "path": "a.obj", "thickness": -1}"#, "`thickness`"),
            (r#"{"type": "mesh", "path": "a.obj", "translate": [0, 1e300, 0]}"#, "`translate` is too large"),
            (r#"{"type": "mesh", "path": "a.obj", "rotate": {"axis": [0, 0, 0], "angle_deg": 9}}"#, "`rotate.axis`"),
            (r#"{"type": "mesh", "path": "a.obj", "rotate": {"axis": [0, 1, 0]}}"#, "`rotate`"),
            (r#"{"radius": 1}"#, "missing `type`"),
            (r#"{"type": "sphere", "center": [0, 0, 0], "radius": 1e300}"#, "`radius` is too large"),
            (r#"{"type": "box", "min": [-1e300, -1, -1], "max": [1, 1, 1]}"#, "`min` is too large"),
            (r#"{"type": "sphere", "center": [0, null, 0], "radius": 1}"#, "`center` must hold finite numbers only"),
            (
                r#"{"type": "sphere", "center": [0, 0, 0], "radius": null}"#,
                "`radius` must hold finite numbers only (not nan, inf or null)",
            ),
        ] {
            let message = ColliderSpec::from_entry(entry(text)).expect_err(text).to_string();
            assert!(message.contains(words), "{text}: {message}");
        }
    }

    #[test]
    fn contact_settings_refuse_negative_values() {
        assert!(ContactSettings { thickness: Some(-1.0), ..Default::default() }.validate().is_err());
        assert!(ContactSettings { friction: -0.5, ..Default::default() }.validate().is_err());
        assert!(ContactSettings { thickness: Some(1e300), ..Default::default() }.validate().is_err());
        assert!(ContactSettings::default().validate().is_ok());
    }
}

#[cfg(test)]
mod direction_tests {
    use super::*;

    #[test]
    fn a_placed_mesh_collider_is_the_mesh_moved_by_its_placement() {
        // A closed box mesh written as it is, and placed: turned 90° about z through (1, 0, 0)
        // (file coordinates), then moved by (0, 2, 0). Every query of the placed collider is the
        // plain one's at the query point mapped back.
        let dir = tempfile::tempdir().expect("a temporary folder");
        let cube = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
                    f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n\
                    f 4 7 3\nf 4 8 7\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n";
        std::fs::write(dir.path().join("cube.obj"), cube).expect("written");
        let mesh = |translate, rotate| ColliderSpec {
            shape: ShapeSpec::Mesh { path: "cube.obj".into(), closed: None, thickness: None, translate, rotate },
            friction: 0.0,
            velocity: [0.0; 3],
            spin: None,
        };
        let build =
            |spec: ColliderSpec| spec.build(&WorkingFrame::IDENTITY, dir.path(), 0.01).expect("a mesh collider");
        let plain = build(mesh([0.0; 3], None));
        let rotate = Rotate { axis: [0.0, 0.0, 1.0], angle_deg: 90.0, center: Some([1.0, 0.0, 0.0]) };
        let placed = build(mesh([0.0, 2.0, 0.0], Some(rotate)));
        let place = mesh_placement([0.0, 2.0, 0.0], Some(&rotate));
        let turn = glam::DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
        assert!((place(DVec3::ZERO) - DVec3::new(1.0, 1.0, 0.0)).length() < 1e-12, "{}", place(DVec3::ZERO));
        for p in [DVec3::new(0.2, 0.3, 0.1), DVec3::new(2.0, -1.0, 0.5), DVec3::new(0.5, 0.5, 0.5)] {
            let (a, b) = (plain.closest_at(p, 0.0), placed.closest_at(place(p), 0.0));
            assert!((a.distance - b.distance).abs() < 1e-12, "{p}: {} against {}", a.distance, b.distance);
            assert!((place(a.point) - b.point).length() < 1e-12 && (turn * a.normal - b.normal).length() < 1e-12);
        }
    }

    #[test]
    fn a_closed_mesh_inside_out_inconsistent_or_flat_is_refused() {
        let cube: Vec<DVec3> =
            (0..8).map(|i| DVec3::new(f64::from(i & 1), f64::from((i >> 1) & 1), f64::from(i >> 2))).collect();
        // Outward: −z, +z, −y, +y, −x, +x.
        let outward: Vec<[u32; 3]> = vec![
            [0, 2, 3],
            [0, 3, 1],
            [4, 5, 7],
            [4, 7, 6],
            [0, 1, 5],
            [0, 5, 4],
            [2, 6, 7],
            [2, 7, 3],
            [0, 4, 6],
            [0, 6, 2],
            [1, 3, 7],
            [1, 7, 5],
        ];
        assert_eq!(closed_mesh_defect(&cube, &outward), None);
        let inward: Vec<[u32; 3]> = outward.iter().map(|&[a, b, c]| [a, c, b]).collect();
        let message = closed_mesh_defect(&cube, &inward).expect("inside out");
        assert!(message.contains("point inward") && message.contains("-1.000e0"), "{message}");
        let mut one_flipped = outward.clone();
        one_flipped[3] = [4, 6, 7];
        let message = closed_mesh_defect(&cube, &one_flipped).expect("one face flipped");
        assert!(message.contains("not consistently oriented") && message.contains("triangles 3 and 8"), "{message}");
        // A square with both sides as faces (the back split along the other diagonal): every
        // edge twice, consistently oriented, nothing enclosed.
        let square = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 0.0, 1.0), DVec3::Z];
        let flat = [[0, 1, 2], [2, 3, 0], [1, 0, 3], [3, 2, 1]];
        assert!(every_edge_twice(&flat));
        let message = closed_mesh_defect(&square, &flat).expect("flat");
        assert!(message.contains("no volume"), "{message}");
    }

    #[test]
    fn a_long_normal_is_a_unit_normal() {
        let spec = ColliderSpec {
            shape: ShapeSpec::Plane { point: [0.0, -1.0, 0.0], normal: [0.0, 1e11, 0.0] },
            friction: 0.0,
            velocity: [0.0; 3],
            spin: None,
        };
        let c = spec.build(&WorkingFrame::IDENTITY, std::path::Path::new("."), 0.0).expect("a plane");
        let p = c.closest_at(DVec3::new(0.0, 0.5, 0.0), 0.0);
        assert!((p.distance - 1.5).abs() < 1e-12 && (p.normal - DVec3::Y).length() < 1e-12, "{p:?}");
    }
}
