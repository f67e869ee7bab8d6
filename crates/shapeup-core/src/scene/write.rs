//! Writing a [`Scene`] back to TOML (what the editor saves), in the schema [`Scene::parse`]
//! reads: the text parses back to an equal scene (except `base_dir` and `file`, which come from
//! where it is read).

use super::{Mode, Scene, SelectionSpec};
use crate::solver::Factorization;
use serde_json::Value as Json;
use std::fmt::Write as _;
use toml::Value;

impl Scene {
    /// The scene as TOML text: `[mesh]` (path, normalize, and tetrahedralize and start when set), every
    /// field of `[solver]`, `[output]` when set, then one `[[constraints]]` entry per group with its type, name,
    /// weight, selection (`vertices`, `box` or `sphere`; none for all vertices), targets
    /// (`targets = [[x, y, z], …]` when explicit, else `translate` / `rotate`) and options.
    ///
    /// Floats are written in Rust's shortest round-trip form, so [`Scene::parse`] of the text
    /// gives back the same numbers bit for bit. JSON `null` options (which no constraint type
    /// takes) are left out.
    pub fn to_toml_string(&self) -> String {
        let mut out = String::new();
        out.push_str("[mesh]\n");
        match &self.mesh.generate {
            Some(generated) => {
                let table = toml::Value::try_from(generated).unwrap_or(Value::Table(toml::Table::new()));
                line(&mut out, "generate", table);
            }
            None => line(&mut out, "path", Value::String(self.mesh.path.to_string_lossy().into_owned())),
        }
        line(&mut out, "normalize", Value::Boolean(self.mesh.normalize));
        if self.mesh.tetrahedralize {
            line(&mut out, "tetrahedralize", Value::Boolean(true));
        }
        if let Some(start) = &self.mesh.start {
            line(&mut out, "start", Value::String(start.to_string_lossy().into_owned()));
        }
        if let Some(units) = self.mesh.units {
            line(&mut out, "units", Value::String(units.name().into()));
        }

        let s = &self.solver;
        out.push_str("\n[solver]\n");
        let mode = match s.mode {
            Mode::Static => "static",
            Mode::Dynamic => "dynamic",
        };
        line(&mut out, "mode", Value::String(mode.into()));
        line(&mut out, "iterations", integer(s.iterations as u64));
        line(&mut out, "steps", integer(s.steps as u64));
        line(&mut out, "tolerance", Value::Float(s.tolerance));
        line(&mut out, "time_step", Value::Float(s.time_step));
        line(&mut out, "gravity", vec3(s.gravity));
        line(&mut out, "stiffness", Value::Float(s.stiffness));
        line(&mut out, "damping", Value::Float(s.damping));
        line(&mut out, "density", Value::Float(s.density));
        let factorization = match s.factorization {
            Factorization::Auto => "auto",
            Factorization::Simplicial => "simplicial",
            Factorization::Supernodal => "supernodal",
        };
        line(&mut out, "factorization", Value::String(factorization.into()));
        line(&mut out, "acceleration", Value::String(s.acceleration.name().into()));
        line(&mut out, "anderson_window", integer(s.anderson_window as u64));
        line(&mut out, "lbfgs_memory", integer(s.lbfgs_memory as u64));

        let o = &self.output;
        if o.path.is_some() || o.report.is_some() {
            out.push_str("\n[output]\n");
            for (key, path) in [("path", &o.path), ("report", &o.report)] {
                if let Some(p) = path {
                    line(&mut out, key, Value::String(p.to_string_lossy().into_owned()));
                }
            }
        }

        if let Some(m) = &self.material {
            out.push_str("\n[material]\n");
            line(&mut out, "model", Value::String(m.model.clone()));
            for (key, value) in [
                ("youngs_modulus", m.youngs_modulus),
                ("poisson_ratio", m.poisson_ratio),
                ("density", m.density),
                ("thickness", m.thickness),
            ] {
                if let Some(v) = value {
                    line(&mut out, key, Value::Float(v));
                }
            }
        }
        if self.loads != Default::default() {
            out.push_str("\n[loads]\n");
        }
        if let Some(p) = self.loads.pressure {
            line(&mut out, "pressure", Value::Float(p));
        }
        if let Some(w) = &self.loads.wind {
            let mut table = toml::map::Map::new();
            table.insert("velocity".into(), Value::Array(w.velocity.iter().map(|&x| Value::Float(x)).collect()));
            for (key, v) in [("drag", w.drag), ("lift", w.lift), ("air_density", w.air_density)] {
                table.insert(key.into(), Value::Float(v));
            }
            line(&mut out, "wind", Value::Table(table));
        }

        for group in &self.groups {
            out.push_str("\n[[constraints]]\n");
            line(&mut out, "type", Value::String(group.kind.clone()));
            line(&mut out, "name", Value::String(group.name.clone()));
            line(&mut out, "weight", Value::Float(group.weight));
            match &group.selection {
                SelectionSpec::All => {}
                SelectionSpec::Vertices(list) => {
                    let list = list.iter().map(|&v| integer(v as u64)).collect();
                    line(&mut out, "vertices", Value::Array(list));
                }
                SelectionSpec::Faces(list) => {
                    let list = list.iter().map(|&f| integer(f as u64)).collect();
                    line(&mut out, "faces", Value::Array(list));
                }
                SelectionSpec::Box { min, max } => {
                    let mut table = toml::Table::new();
                    table.insert("min".into(), vec3(*min));
                    table.insert("max".into(), vec3(*max));
                    line(&mut out, "box", Value::Table(table));
                }
                SelectionSpec::Physical(name) => line(&mut out, "physical", Value::String(name.clone())),
                SelectionSpec::Sphere { center, radius } => {
                    let mut table = toml::Table::new();
                    table.insert("center".into(), vec3(*center));
                    table.insert("radius".into(), Value::Float(*radius));
                    line(&mut out, "sphere", Value::Table(table));
                }
            }
            let t = &group.targets;
            if let Some(explicit) = &t.explicit {
                line(&mut out, "targets", Value::Array(explicit.iter().map(|&p| vec3(p)).collect()));
            } else {
                // The parser only reads targets on types with targets; others never set them.
                if t.translate != [0.0; 3] {
                    line(&mut out, "translate", vec3(t.translate));
                }
                if let Some(r) = &t.rotate {
                    line(&mut out, "rotate", turn_table(r.axis, ("angle_deg", r.angle_deg), r.center));
                }
            }
            if let Some(spin) = &t.spin {
                line(&mut out, "spin", turn_table(spin.axis, ("deg_per_s", spin.deg_per_s), spin.center));
            }
            for (key, value) in &group.options {
                if let Some(value) = from_json(value) {
                    line(&mut out, key, value);
                }
            }
        }

        let c = &self.contact;
        if *c != crate::contact::ContactSettings::default() {
            out.push_str("\n[contact]\n");
            line(&mut out, "self_collision", Value::Boolean(c.self_collision));
            if let Some(t) = c.thickness {
                line(&mut out, "thickness", Value::Float(t));
            }
            line(&mut out, "friction", Value::Float(c.friction));
        }
        for collider in &self.colliders {
            out.push_str("\n[[colliders]]\n");
            for (key, value) in &collider.to_entry() {
                if let Some(value) = from_json(value) {
                    line(&mut out, key, value);
                }
            }
        }
        out
    }
}

/// `{ axis = […], <amount> = x, center = […] }` of a `rotate` or `spin` (no center when `None`).
fn turn_table(axis: [f64; 3], (key, amount): (&str, f64), center: Option<[f64; 3]>) -> Value {
    let mut table = toml::Table::new();
    table.insert("axis".into(), vec3(axis));
    table.insert(key.into(), Value::Float(amount));
    if let Some(c) = center {
        table.insert("center".into(), vec3(c));
    }
    Value::Table(table)
}

/// Appends `key = value` (the value inline).
fn line(out: &mut String, key: &str, value: Value) {
    // Writing to a String cannot fail.
    let _ = writeln!(out, "{} = {value}", toml_key(key));
}

/// A key as written: bare when it can be, else a quoted string.
fn toml_key(key: &str) -> String {
    let bare = !key.is_empty() && key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if bare { key.to_string() } else { Value::String(key.to_string()).to_string() }
}

/// A TOML integer (they are i64; larger counts saturate, and never occur).
fn integer(v: u64) -> Value {
    Value::Integer(i64::try_from(v).unwrap_or(i64::MAX))
}

fn vec3(v: [f64; 3]) -> Value {
    Value::Array(v.iter().map(|&x| Value::Float(x)).collect())
}

/// A JSON option value as TOML; `None` for `null`, which TOML cannot represent.
fn from_json(value: &Json) -> Option<Value> {
    Some(match value {
        Json::Null => return None,
        Json::Bool(b) => Value::Boolean(*b),
        Json::Number(n) => match n.as_i64() {
            Some(i) => Value::Integer(i),
            None => Value::Float(n.as_f64().unwrap_or(f64::NAN)),
        },
        Json::String(s) => Value::String(s.clone()),
        Json::Array(items) => Value::Array(items.iter().filter_map(from_json).collect()),
        Json::Object(map) => {
            Value::Table(map.iter().filter_map(|(k, v)| from_json(v).map(|v| (k.clone(), v))).collect())
        }
    })
}

#[cfg(test)]
mod tests {
    use super::super::{GroupSpec, MeshSettings, Rotate, SceneFormat, SolverSettings, Targets};
    use super::*;
    use std::path::{Path, PathBuf};

    fn parse(text: &str) -> Scene {
        Scene::parse(text, SceneFormat::Toml, Path::new("s.toml"), PathBuf::from("dir")).unwrap()
    }

    fn group(kind: &str, name: &str, weight: f64, selection: SelectionSpec) -> GroupSpec {
        GroupSpec {
            kind: kind.into(),
            name: name.into(),
            weight,
            selection,
            targets: Targets::default(),
            options: Default::default(),
        }
    }

    #[test]
    fn written_scene_parses_back_equal() {
        let mut handle = group("position", "handle \"1\"", 1.0, SelectionSpec::Vertices(vec![3, 1, 4]));
        handle.targets.explicit = Some(vec![[0.1, -0.2, 1e-300], [1.0 / 3.0, 2.0, -0.0], [1e20, 5.0, 0.7]]);
        let mut rotated =
            group("position", "rot", 2.5, SelectionSpec::Sphere { center: [0.0, 1.0, 2.0], radius: 0.25 });
        rotated.targets.translate = [0.1, 0.0, 0.3];
        rotated.targets.rotate = Some(Rotate { axis: [0.0, 1.0, 0.0], angle_deg: 30.0, center: Some([1.0, 2.0, 3.0]) });
        rotated.targets.spin = Some(super::super::Spin { axis: [1.0, 0.0, 0.0], deg_per_s: 45.5, center: None });
        let mut strain = group("triangle_strain", "shape", 10.0, SelectionSpec::All);
        strain.options.insert("strain_freedom".into(), serde_json::json!(0.1));
        let mut floor = group("floor", "floor", 1.0, SelectionSpec::Box { min: [-1.0; 3], max: [1.0, 2.0, 3.0] });
        floor.options.insert("height".into(), serde_json::json!(-1));
        floor.options.insert("push".into(), serde_json::json!(0.5));
        let scene = Scene {
            mesh: MeshSettings {
                path: PathBuf::from("meshes/my mesh.obj"),
                generate: None,
                normalize: false,
                tetrahedralize: true,
                start: Some(PathBuf::from("meshes/start shape.obj")),
                units: None,
            },
            solver: SolverSettings {
                mode: Mode::Dynamic,
                iterations: 7,
                factorization: Factorization::Supernodal,
                gravity: [0.0, -1.5, 0.1],
                ..SolverSettings::default()
            },
            groups: vec![strain, group("bending", "bend", 1e-4, SelectionSpec::All), handle, rotated, floor],
            colliders: vec![
                crate::contact::ColliderSpec {
                    shape: crate::contact::ShapeSpec::Sphere { center: [0.0, -0.5, 0.25], radius: 0.3 },
                    friction: 0.4,
                    velocity: [0.0, 0.0, 0.1],
                    spin: None,
                },
                crate::contact::ColliderSpec {
                    shape: crate::contact::ShapeSpec::Box {
                        min: [-1.0, -2.0, -1.0],
                        max: [1.0, -1.9, 1.0],
                        rotate: Some(Rotate { axis: [0.0, 0.0, 1.0], angle_deg: 10.0, center: None }),
                    },
                    friction: 0.0,
                    velocity: [0.0; 3],
                    spin: Some(super::super::Spin {
                        axis: [0.0, 1.0, 0.0],
                        deg_per_s: 30.0,
                        center: Some([0.0, 0.0, 0.0]),
                    }),
                },
            ],
            contact: crate::contact::ContactSettings { self_collision: true, thickness: Some(0.01), friction: 0.2 },
            output: super::super::OutputSettings { path: Some("out/result.obj".into()), report: None },
            material: None,
            loads: Default::default(),
            base_dir: PathBuf::from("dir"),
            file: PathBuf::from("s.toml"),
        };
        let text = scene.to_toml_string();
        assert_eq!(parse(&text), scene, "{text}");
    }

    #[test]
    fn generated_meshes_round_trip() {
        for generate in [
            "{ kind = \"cloth\", vertices = [4, 5], size = [1.5, 2.0] }",
            "{ kind = \"tet_box\", cells = [2, 3, 4], size = [1.0, 0.5, 0.25] }",
            "{ kind = \"sphere\", subdivisions = 2, radius = 0.5 }",
        ] {
            let scene = parse(&format!("[mesh]\ngenerate = {generate}\n[[constraints]]\ntype = \"edge_spring\"\n"));
            assert!(scene.mesh.generate.is_some());
            assert_eq!(parse(&scene.to_toml_string()), scene);
        }
    }

    #[test]
    fn defaults_round_trip() {
        let scene = parse("[mesh]\npath = \"m.obj\"\n[[constraints]]\ntype = \"edge_spring\"\n");
        assert_eq!(parse(&scene.to_toml_string()), scene);
    }
}
