//! From scene text (TOML or JSON) to a validated [`Scene`].

use super::strict::{Entry, EntryList, OneTable, StrictValue, spelled};
use super::{
    GroupSpec, MATERIAL_ITERATIONS, MATERIAL_TOLERANCE, MaterialSettings, MeshSettings, OutputSettings, Scene,
    SceneError, SolverSettings,
};
use crate::solver::{MAX_ANDERSON_WINDOW, MAX_LBFGS_MEMORY};
use crate::text::{plain_words, value_as};
use serde::Deserialize;
use serde_json::{Map, Value};
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    #[serde(deserialize_with = "mesh_table")]
    mesh: MeshSettings,
    #[serde(default, deserialize_with = "solver_table")]
    solver: SolverSettings,
    #[serde(default, deserialize_with = "constraint_list")]
    constraints: Vec<Entry>,
    #[serde(default, deserialize_with = "collider_list")]
    colliders: Vec<Entry>,
    #[serde(default, deserialize_with = "contact_table")]
    contact: crate::contact::ContactSettings,
    #[serde(default, deserialize_with = "output_table")]
    output: OutputSettings,
    #[serde(default, deserialize_with = "material_table")]
    material: Option<MaterialSettings>,
    #[serde(default, deserialize_with = "loads_table")]
    loads: super::LoadSettings,
}

fn loads_table<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<super::LoadSettings, D::Error> {
    deserializer.deserialize_any(OneTable("loads", std::marker::PhantomData))
}

fn material_table<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<Option<MaterialSettings>, D::Error> {
    deserializer.deserialize_any(OneTable("material", std::marker::PhantomData)).map(Some)
}

fn constraint_list<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<Vec<Entry>, D::Error> {
    deserializer.deserialize_any(EntryList("constraints"))
}

fn collider_list<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<Vec<Entry>, D::Error> {
    deserializer.deserialize_any(EntryList("colliders"))
}

/// Each top-level table as one table ([`OneTable`]).
fn mesh_table<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<MeshSettings, D::Error> {
    deserializer.deserialize_any(OneTable("mesh", std::marker::PhantomData))
}

fn solver_table<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<SolverSettings, D::Error> {
    deserializer.deserialize_any(OneTable("solver", std::marker::PhantomData))
}

fn contact_table<'de, D: serde::Deserializer<'de>>(
    deserializer: D,
) -> Result<crate::contact::ContactSettings, D::Error> {
    deserializer.deserialize_any(OneTable("contact", std::marker::PhantomData))
}

fn output_table<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<OutputSettings, D::Error> {
    deserializer.deserialize_any(OneTable("output", std::marker::PhantomData))
}

/// Scene file syntax.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneFormat {
    /// TOML (`.toml`).
    Toml,
    /// JSON (`.json`).
    Json,
}

impl Scene {
    /// Reads and parses a scene file (`.toml` or `.json`).
    ///
    /// # Errors
    /// [`SceneError`] naming the file, and the line or entry.
    pub fn from_file(path: &Path) -> Result<Scene, SceneError> {
        let (text, format, base_dir) = read_scene_file(path)?;
        Scene::parse(&text, format, path, base_dir)
    }

    /// Reads a scene file as [`Scene::from_file`] does, with `overrides` applied to its entries
    /// before they are checked (see [`Scene::parse_with_overrides`]): the scene a parameter
    /// sweep runs.
    ///
    /// # Errors
    /// As [`Scene::from_file`]; [`SceneError::Override`] for a key that names no entry.
    pub fn from_file_with_overrides(path: &Path, overrides: &[(String, Value)]) -> Result<Scene, SceneError> {
        let (text, format, base_dir) = read_scene_file(path)?;
        Scene::parse_with_overrides(&text, format, path, base_dir, overrides)
    }

    /// This scene with `overrides` applied (see [`Scene::parse_with_overrides`]), checked again
    /// as a scene file is: an override that makes the scene invalid is refused with the
    /// message the same file would get.
    ///
    /// # Errors
    /// [`SceneError::Override`] for a key that names no entry; [`SceneError::Parse`] or
    /// [`SceneError::Invalid`] for a value the scene contract refuses.
    pub fn with_overrides(&self, overrides: &[(String, Value)]) -> Result<Scene, SceneError> {
        // The TOML text parses back to an equal scene (write.rs).
        let text = self.to_toml_string();
        Scene::parse_with_overrides(&text, SceneFormat::Toml, &self.file, self.base_dir.clone(), overrides)
    }

    /// Parses scene text with dotted overrides applied to its tree of tables before the scene is
    /// checked: `"solver.iterations"`, `"constraints.2.weight"`, `"output.path"`, `"mesh.generate"`.
    /// A table on the way that is missing is created; a list index must name an entry that
    /// exists. The values replace what the text gives (a whole table or list for a table's or
    /// list's key).
    ///
    /// # Errors
    /// [`SceneError::Override`] for a key that names no entry; otherwise as [`Scene::parse`]
    /// (messages name the key, without a line: the checked tree is no longer the text).
    pub fn parse_with_overrides(
        text: &str,
        format: SceneFormat,
        path: &Path,
        base_dir: PathBuf,
        overrides: &[(String, Value)],
    ) -> Result<Scene, SceneError> {
        let parse_error = |message: String| SceneError::Parse { path: path.into(), message };
        let mut tree: Value = match format {
            SceneFormat::Toml => StrictValue::read_toml(text).map_err(|e| parse_error(toml_message(text, &e)))?,
            SceneFormat::Json => StrictValue::read_json(text).map_err(|e| parse_error(json_message(text, &e)))?,
        };
        for (key, value) in overrides {
            apply_override(&mut tree, key, value.clone())?;
        }
        // The tree has no lines: a message names the key it is about, as the overrides do.
        let given = SolverKeys::of(&tree);
        let raw: RawScene = serde_path_to_error::deserialize(tree)
            .map_err(|e| parse_error(format!("{}: {}", e.path(), plain_words(&e.inner().to_string()))))?;
        Scene::from_raw(raw, path, base_dir).map(|scene| given.material_defaults(scene))
    }

    /// Parses scene text; `path` is only used in messages, `base_dir` resolves the mesh path.
    ///
    /// # Errors
    /// [`SceneError::Parse`] or [`SceneError::Invalid`].
    pub fn parse(text: &str, format: SceneFormat, path: &Path, base_dir: PathBuf) -> Result<Scene, SceneError> {
        let parse_error = |message: String| SceneError::Parse { path: path.into(), message };
        let raw: RawScene = match format {
            SceneFormat::Toml => toml::from_str(text).map_err(|e| parse_error(toml_message(text, &e)))?,
            SceneFormat::Json => serde_json::from_str(text).map_err(|e| parse_error(json_message(text, &e)))?,
        };
        let scene = Scene::from_raw(raw, path, base_dir)?;
        if scene.material()?.is_none() {
            return Ok(scene);
        }
        // Which [solver] keys the text gives (it parsed above, so it parses again).
        let tree = match format {
            SceneFormat::Toml => StrictValue::read_toml(text).ok(),
            SceneFormat::Json => StrictValue::read_json(text).ok(),
        };
        Ok(tree.map_or(SolverKeys::default(), |t| SolverKeys::of(&t)).material_defaults(scene))
    }

    /// Checks a scene's tables and entries (the part of [`Scene::parse`] after the syntax).
    fn from_raw(raw: RawScene, path: &Path, base_dir: PathBuf) -> Result<Scene, SceneError> {
        let mesh_error = |message: String| SceneError::Invalid { path: path.into(), entry: "[mesh]".into(), message };
        match (&raw.mesh.generate, raw.mesh.path.as_os_str().is_empty()) {
            (Some(g), true) => g.validate().map_err(|e| mesh_error(e.to_string()))?,
            (Some(_), false) => return Err(mesh_error("give either path or generate, not both".into())),
            (None, true) => return Err(mesh_error("missing path (a mesh file), or generate".into())),
            (None, false) => {}
        }
        validate_solver(&raw.solver).map_err(|e| SceneError::Invalid {
            path: path.into(),
            entry: "[solver]".into(),
            message: e.0,
        })?;
        let mut groups: Vec<GroupSpec> = Vec::with_capacity(raw.constraints.len());
        for (i, entry) in raw.constraints.into_iter().enumerate() {
            let entry = entry.table().map_err(|message| SceneError::Invalid {
                path: path.into(),
                entry: format!("constraints[{i}]"),
                message,
            })?;
            let name = entry.get("name").and_then(Value::as_str).map(|n| format!(" (\"{n}\")")).unwrap_or_default();
            let existing: Vec<&str> = groups.iter().map(|g| g.name.as_str()).collect();
            let group = GroupSpec::from_entry_among(entry, &existing).map_err(|e| SceneError::Invalid {
                path: path.into(),
                entry: format!("constraints[{i}]{name}"),
                message: plain_words(&e.to_string()),
            })?;
            groups.push(group);
        }
        raw.contact.validate().map_err(|e| SceneError::Invalid {
            path: path.into(),
            entry: "[contact]".into(),
            message: e.to_string(),
        })?;
        let colliders = raw
            .colliders
            .into_iter()
            .enumerate()
            .map(|(i, entry)| {
                let invalid =
                    |message| SceneError::Invalid { path: path.into(), entry: format!("colliders[{i}]"), message };
                crate::contact::ColliderSpec::from_entry(entry.table().map_err(invalid)?)
                    .map_err(|e| invalid(plain_words(&e.to_string())))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let scene = Scene {
            mesh: raw.mesh,
            solver: raw.solver,
            groups,
            colliders,
            contact: raw.contact,
            output: raw.output,
            material: raw.material,
            loads: raw.loads,
            base_dir,
            file: path.into(),
        };
        // A material's keys, and units only with a material.
        if scene.material()?.is_none()
            && let Some(units) = scene.mesh.units
        {
            return Err(mesh_error(format!(
                "units = \"{}\" needs a [material] with a model (stvk, corotated, neo_hookean; \"projective\" has none): with one the solver works in metres and the units convert the mesh",
                units.name()
            )));
        }
        Ok(scene)
    }

    /// The `[material]` table's material, checked: `None` without one (or with `model =
    /// "projective"`).
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming `[material]` and its first bad key.
    pub fn material(&self) -> Result<Option<crate::materials::Material>, SceneError> {
        let Some(settings) = &self.material else { return Ok(None) };
        settings.material().map_err(|message| SceneError::Invalid {
            path: self.file.clone(),
            entry: "[material]".into(),
            message,
        })
    }
}

/// Which `[solver]` keys a scene's text gives, for the defaults a material changes.
#[derive(Debug, Default)]
struct SolverKeys {
    iterations: bool,
    tolerance: bool,
}

impl SolverKeys {
    fn of(tree: &Value) -> SolverKeys {
        let solver = tree.get("solver");
        let given = |key: &str| solver.and_then(|s| s.get(key)).is_some();
        SolverKeys { iterations: given("iterations"), tolerance: given("tolerance") }
    }

    /// With a material, a solve runs to [`MATERIAL_TOLERANCE`] under a guard of
    /// [`MATERIAL_ITERATIONS`] unless the scene says otherwise (a material's solve that stops
    /// at 10 iterations is not the material's behaviour: it freezes).
    fn material_defaults(&self, mut scene: Scene) -> Scene {
        if matches!(scene.material(), Ok(Some(_))) {
            if !self.iterations {
                scene.solver.iterations = MATERIAL_ITERATIONS;
            }
            if !self.tolerance {
                scene.solver.tolerance = MATERIAL_TOLERANCE;
            }
        }
        scene
    }
}

/// The text of a scene file, its syntax (from the extension) and the folder its paths start
/// from.
fn read_scene_file(path: &Path) -> Result<(String, SceneFormat, PathBuf), SceneError> {
    let format = match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("toml") => SceneFormat::Toml,
        Some("json") => SceneFormat::Json,
        _ => {
            return Err(SceneError::Parse {
                path: path.into(),
                message: "a scene file must end in .toml or .json".into(),
            });
        }
    };
    // UTF-8 (a byte-order mark, which is not TOML or JSON, removed) or UTF-16 (Windows
    // editors' "Unicode"), decoded; text that is neither is a format error with its offset.
    let text = crate::io::read_text_file(path).map_err(|source| match crate::io::DecodeError::of(&source) {
        Some(e) => SceneError::Parse { path: path.into(), message: e.to_string() },
        None => SceneError::Read { path: path.into(), source },
    })?;
    let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    Ok((text, format, base_dir))
}

/// Sets the dotted `key` of `tree` to `value`, as the Python package's `Scene.load(path,
/// overrides)` always has: tables on the way are created when missing, list indices must exist.
fn apply_override(tree: &mut Value, key: &str, value: Value) -> Result<(), SceneError> {
    let fail = |problem: String| SceneError::Override { key: key.into(), problem };
    let parts: Vec<&str> = key.split('.').collect();
    let (last, path) = parts.split_last().ok_or_else(|| fail("no such entry".into()))?;
    let index = |part: &str, len: usize| {
        (!part.is_empty() && part.bytes().all(|b| b.is_ascii_digit()))
            .then(|| part.parse::<usize>().ok())
            .flatten()
            .filter(|&i| i < len)
    };
    let mut node = tree;
    for (i, part) in path.iter().enumerate() {
        let not_an_entry = || fail(format!("{} is not an entry of the scene", parts[..=i].join(".")));
        node = match node {
            Value::Array(list) => {
                let at = index(part, list.len()).ok_or_else(not_an_entry)?;
                &mut list[at]
            }
            Value::Object(map) => map.entry(part.to_string()).or_insert_with(|| Value::Object(Map::new())),
            _ => return Err(not_an_entry()),
        };
    }
    match node {
        Value::Array(list) => {
            let at = index(last, list.len()).ok_or_else(|| fail("no such entry".into()))?;
            list[at] = value;
        }
        Value::Object(map) => {
            map.insert(last.to_string(), value);
        }
        _ => return Err(fail("no such entry".into())),
    }
    Ok(())
}

/// JSON `text` (the Python package's settings and entries, written by the package) as a `T`,
/// with a message that names the key it is about in the scene's words: `iterations: invalid
/// value: integer `-1`, expected a whole number ≥ 0`, not serde's Rust type and position in
/// the internal text.
///
/// # Errors
/// That message.
pub fn from_json_entry<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, String> {
    value_as(serde_json::from_str(text).map_err(|e| e.to_string())?)
}

/// One line from a TOML error: its message with the line and column of its span.
fn toml_message(text: &str, e: &toml::de::Error) -> String {
    let message = plain_words(&e.message().trim().replace('\n', " "));
    // A JSON text in a file named .toml.
    if serde_json::from_str::<serde_json::Value>(text).is_ok_and(|v| v.is_object()) {
        return "the file is JSON but its name ends in .toml: rename it to .json".into();
    }
    match e.span() {
        Some(span) => {
            let mut start = span.start.min(text.len());
            while !text.is_char_boundary(start) {
                start -= 1;
            }
            let before = &text[..start];
            let line = before.matches('\n').count() + 1;
            let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            // Quote the line: a type error's message names the value but not the key.
            let quoted = text.lines().nth(line - 1).map(str::trim).filter(|l| !l.is_empty() && l.len() <= 80);
            match quoted {
                Some(l) => format!("line {line}, column {column}: {message} (in `{l}`)"),
                None => format!("line {line}, column {column}: {message}"),
            }
        }
        // toml's deserializer stops past 128 levels without a span: point at the line whose
        // keys and brackets nest deepest.
        None if message.contains("recursion limit") => {
            let depth =
                |l: &str| l.split('=').next().map_or(0, |key| key.matches('.').count()) + l.matches(['[', '{']).count();
            match text.lines().enumerate().max_by_key(|&(i, l)| (depth(l), std::cmp::Reverse(i))) {
                Some((i, _)) => format!("line {}: nested too deep ({message})", i + 1),
                None => message,
            }
        }
        None => message,
    }
}

/// One line from a JSON error: its message with its line and column, and the key of the value
/// it stopped in (serde_json names no key: `"thickness": 1e400` is "number out of range").
fn json_message(text: &str, e: &serde_json::Error) -> String {
    let full = plain_words(&e.to_string());
    if e.line() == 0 {
        return full;
    }
    let (line, column) = (e.line(), e.column());
    let message = full.strip_suffix(&format!(" at line {line} column {column}")).unwrap_or(&full);
    // serde_json's column counts the bytes of its line before the error.
    let start: usize = text.split_inclusive('\n').take(line - 1).map(str::len).sum();
    // What a syntax error most often is: a TOML text in a file named .json, or a comment.
    if e.is_syntax() {
        if toml::from_str::<toml::Table>(text).is_ok() {
            return "the file is TOML but its name ends in .json: rename it to .toml".into();
        }
        let at = text.get(start + column.saturating_sub(1)..).unwrap_or_default();
        if at.starts_with("//") || at.starts_with("/*") || (at.starts_with('/') && column > 0) {
            return format!(
                "line {line}, column {column}: JSON has no comments; remove them, or write the scene in TOML (comments start with #)"
            );
        }
    }
    // A message that names the key or the entry it is in already (`colliders` must be a
    // list…) needs no more.
    let named = |key: &str| {
        key.match_indices(['.', '['])
            .map(|(at, _)| &key[..at])
            .chain([key])
            .any(|part| message.contains(&format!("`{part}`")))
    };
    match json_key_at(text, start + column) {
        Some(key) if !named(&key) => format!("line {line}, column {column}: {message} (in `{key}`)"),
        _ => format!("line {line}, column {column}: {message}"),
    }
}

/// The key (`contact.thickness`, `colliders[0].center`) of the value that JSON `text`'s first
/// `end` bytes stop in; `None` at the top level. The text before a serde_json error is
/// well-formed so far: strings, brackets, colons and commas are all it takes.
fn json_key_at(text: &str, end: usize) -> Option<String> {
    enum Level {
        Table { key: Option<String>, at_value: bool },
        List(usize),
    }
    let mut end = end.min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let bytes = &text.as_bytes()[..end];
    let mut levels: Vec<Level> = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'"' => {
                let start = i;
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' {
                    i += if bytes[i] == b'\\' { 2 } else { 1 };
                }
                // A string before its table's colon is a key.
                if let Some(Level::Table { key, at_value: false }) = levels.last_mut()
                    && i < bytes.len()
                {
                    *key = serde_json::from_str::<String>(&text[start..=i]).ok();
                }
            }
            b'{' => levels.push(Level::Table { key: None, at_value: false }),
            b'[' => levels.push(Level::List(0)),
            b'}' | b']' => {
                levels.pop();
            }
            b':' => {
                if let Some(Level::Table { at_value, .. }) = levels.last_mut() {
                    *at_value = true;
                }
            }
            b',' => match levels.last_mut() {
                Some(Level::Table { key, at_value }) => (*key, *at_value) = (None, false),
                Some(Level::List(n)) => *n += 1,
                None => {}
            },
            _ => {}
        }
        i += 1;
    }
    let mut path = String::new();
    for level in &levels {
        match level {
            Level::Table { key: Some(key), .. } => {
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(&crate::text::shown(key));
            }
            Level::Table { key: None, .. } => break,
            Level::List(n) => path.push_str(&format!("[{n}]")),
        }
    }
    (!path.is_empty()).then_some(path)
}

/// A `[solver]` value out of range, described.
struct BadSetting(String);

impl From<String> for BadSetting {
    fn from(message: String) -> Self {
        BadSetting(message)
    }
}

impl From<&str> for BadSetting {
    fn from(message: &str) -> Self {
        BadSetting(message.into())
    }
}

fn validate_solver(s: &SolverSettings) -> Result<(), BadSetting> {
    let positive = |name: &str, v: f64| -> Result<(), BadSetting> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(format!("{name} must be a finite number > 0, found {}", spelled(v)).into())
        }
    };
    if !(s.tolerance.is_finite() && s.tolerance >= 0.0) {
        return Err(format!("tolerance must be a finite number ≥ 0, found {}", spelled(s.tolerance)).into());
    }
    positive("time_step", s.time_step)?;
    positive("stiffness", s.stiffness)?;
    positive("density", s.density)?;
    if !(0.0..1.0).contains(&s.damping) {
        return Err(format!("damping must be in [0, 1), found {}", spelled(s.damping)).into());
    }
    if !s.gravity.iter().all(|g| g.is_finite()) {
        let found: Vec<String> = s.gravity.iter().map(|&g| spelled(g)).collect();
        return Err(format!("gravity must be three finite numbers, found [{}]", found.join(", ")).into());
    }
    if !(1..=MAX_ANDERSON_WINDOW).contains(&s.anderson_window) {
        return Err(format!("anderson_window must be in 1..={MAX_ANDERSON_WINDOW}, found {}", s.anderson_window).into());
    }
    if !(1..=MAX_LBFGS_MEMORY).contains(&s.lbfgs_memory) {
        return Err(format!("lbfgs_memory must be in 1..={MAX_LBFGS_MEMORY}, found {}", s.lbfgs_memory).into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SelectionSpec;

    fn parse(text: &str) -> Result<Scene, SceneError> {
        Scene::parse(text, SceneFormat::Toml, Path::new("s.toml"), PathBuf::new())
    }

    #[test]
    fn defaults_and_groups() {
        let s = parse(
            r#"
            [mesh]
            path = "m.obj"
            [[constraints]]
            type = "edge_spring"
            [[constraints]]
            type = "position"
            name = "handle"
            box = { min = [0, 0, 0], max = [1, 1, 1] }
            translate = [0.1, 0, 0]
            "#,
        )
        .unwrap();
        assert!(s.mesh.normalize);
        assert_eq!(s.solver, SolverSettings::default());
        assert_eq!(s.groups[0].weight, 10.0, "default multiplier of edge springs");
        assert_eq!(s.groups[0].name, "edge_spring");
        assert_eq!(s.groups[1].targets.translate, [0.1, 0.0, 0.0]);
        assert!(matches!(s.groups[1].selection, SelectionSpec::Box { .. }));
    }

    /// Messages say what the user wrote, in the scene's words: no Rust type names, the
    /// syntax a misnamed file has, JSON's lack of comments, an empty list or a box turned
    /// inside out as what they are.
    #[test]
    fn solver_settings_say_finite_and_spell_nan_as_toml_does() {
        for (body, words) in [
            ("tolerance = nan", "tolerance must be a finite number ≥ 0, found nan"),
            ("tolerance = inf", "tolerance must be a finite number ≥ 0, found inf"),
            ("stiffness = inf", "stiffness must be a finite number > 0, found inf"),
            ("gravity = [0, nan, 0]", "gravity must be three finite numbers, found [0, nan, 0]"),
        ] {
            let message =
                parse(&format!("[mesh]\npath = \"m.obj\"\n[solver]\n{body}\n")).map(|_| ()).unwrap_err().to_string();
            assert!(message.contains(words), "{body}: {message}");
        }
    }

    #[test]
    fn messages_use_the_scenes_words() {
        let toml =
            |body: &str| parse(&format!("[mesh]\npath = \"m.obj\"\n{body}")).map(|_| ()).unwrap_err().to_string();
        let json = |text: &str| {
            Scene::parse(text, SceneFormat::Json, Path::new("s.json"), PathBuf::new())
                .map(|_| ())
                .unwrap_err()
                .to_string()
        };
        for (message, words) in [
            (toml("[solver]\niterations = -3\n"), "expected a whole number ≥ 0"),
            (toml("[solver]\niterations = 1.5\n"), "expected a whole number ≥ 0"),
            (toml("[solver]\ntolerance = \"x\"\n"), "expected a number"),
            (
                parse("mesh = 3\n").map(|_| ()).unwrap_err().to_string(),
                "`mesh` must be one [mesh] table, found a number",
            ),
            (json("[mesh]\npath = \"m.obj\"\n"), "the file is TOML but its name ends in .json"),
            (json("{\"mesh\": {\"path\": \"m.obj\"} // the mesh\n}"), "line 1, column 28: JSON has no comments"),
            (toml("[[constraints]]\ntype = \"edge_spring\"\nvertices = []\n"), "\"vertices\" = [] selects nothing"),
            (toml("[[constraints]]\ntype = \"plane\"\nfaces = []\n"), "\"faces\" = [] selects nothing"),
            (
                toml("[[constraints]]\ntype = \"position\"\nbox = { min = [0, 2, 0], max = [1, 1, 1] }\n"),
                "min y (2) is greater than max y (1)",
            ),
            (toml("[[constraints]]\ntype = \"position\"\nbox = 1\n"), "expected a table"),
            (toml("[[colliders]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = \"1\"\n"), "expected a number"),
            (toml("[solver]\nsteps = 99999999999999999999999\n"), "(too large)"),
            (
                parse("output = [\"out\", \"r.json\"]\n[mesh]\npath = \"m.obj\"\n")
                    .map(|_| ())
                    .unwrap_err()
                    .to_string(),
                "`output` must be one [output] table (not a list",
            ),
            (toml("[solver]\nmode = 1\n"), "expected a name (a string)"),
            (parse("mesh = [\"m.obj\"]\n").map(|_| ()).unwrap_err().to_string(), "`mesh` must be one [mesh] table"),
            (parse("[mesh]\ngenerate = \"cloth\"\n").map(|_| ()).unwrap_err().to_string(), "kind = \"cloth\""),
        ] {
            assert!(message.contains(words), "{message}");
            for rust in ["usize", "f64", "struct", "i128", "enum", "variant identifier", "wanted"] {
                assert!(!message.contains(rust), "{message}");
            }
        }
        let misnamed =
            Scene::parse("{\"mesh\": {\"path\": \"m.obj\"}}", SceneFormat::Toml, Path::new("s.toml"), PathBuf::new());
        assert!(misnamed.unwrap_err().to_string().contains("the file is JSON but its name ends in .toml"));
    }

    /// TOML spells inf and nan; an entry's number that is either is refused at its line, as
    /// the file spells it (it used to reach the builders as null: "invalid type: null").
    #[test]
    fn an_entrys_infinite_or_nan_number_is_refused_at_its_line() {
        for (value, spelled) in [("nan", "nan"), ("-inf", "-inf"), ("+inf", "inf")] {
            for (entry, line) in [
                (format!("[[constraints]]\ntype = \"edge_spring\"\nweight = {value}\n"), 5),
                (
                    format!(
                        "[[constraints]]\ntype = \"position\"\nvertices = [0]\nspin = {{ axis = [0, 1, 0], deg_per_s = {value} }}\n"
                    ),
                    6,
                ),
                (format!("[[colliders]]\ntype = \"sphere\"\ncenter = [0, {value}, 0]\nradius = 1\n"), 5),
            ] {
                let text = format!("[mesh]\npath = \"m.obj\"\n{entry}");
                let message = parse(&text).map(|_| ()).unwrap_err().to_string();
                assert!(message.contains(&format!("line {line}")), "{value}: {message}");
                // The same through the overrides' path (a parameter sweep's).
                let swept =
                    Scene::parse_with_overrides(&text, SceneFormat::Toml, Path::new("s.toml"), PathBuf::new(), &[])
                        .map(|_| ())
                        .unwrap_err()
                        .to_string();
                assert_eq!(swept, message, "{value}");
                assert!(message.contains(&format!("numbers must be finite, found {spelled}")), "{value}: {message}");
                assert!(!message.contains("null"), "{value}: {message}");
            }
        }
    }

    #[test]
    fn unnamed_groups_follow_one_rule_and_names_are_unique() {
        let s = parse(
            r#"
            [mesh]
            path = "m.obj"
            [[constraints]]
            type = "edge_spring"
            [[constraints]]
            type = "edge_spring"
            [[constraints]]
            type = "edge_spring"
            name = "edge_spring_3"
            [[constraints]]
            type = "edge_spring"
            "#,
        )
        .unwrap();
        let names: Vec<&str> = s.groups.iter().map(|g| g.name.as_str()).collect();
        assert_eq!(names, ["edge_spring", "edge_spring_2", "edge_spring_3", "edge_spring_4"]);

        let e = parse(
            r#"
            [mesh]
            path = "m.obj"
            [[constraints]]
            type = "edge_spring"
            name = "shape"
            [[constraints]]
            type = "bending"
            name = "shape"
            "#,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("constraints[1] (\"shape\")") && e.contains("a group named \"shape\" exists already"),
            "{e}"
        );
    }

    #[test]
    fn unknown_keys_are_named() {
        let e = parse("[mesh]\npath = \"m.obj\"\nnormalise = true\n").unwrap_err().to_string();
        assert!(e.contains("normalise") && e.contains("line 3"), "{e}");
        let e = parse("[mesh]\npath = \"m.obj\"\n[solver]\niteratons = 3\n").unwrap_err().to_string();
        assert!(e.contains("iteratons"), "{e}");
        let e = parse("[mesh]\npath = \"m.obj\"\n[[constraints]]\ntype = \"edge_sprin\"\n").unwrap_err().to_string();
        assert!(e.contains("edge_sprin") && e.contains("constraints[0]"), "{e}");
    }

    #[test]
    fn bad_values_are_rejected() {
        for (body, needle) in [
            ("[[constraints]]\ntype = \"edge_spring\"\nweight = -1\n", "weight"),
            ("[[constraints]]\ntype = \"position\"\nvertices = [-1]\n", "vertices"),
            (
                "[[constraints]]\ntype = \"position\"\nvertices = [1]\nbox = { min = [0,0,0], max = [1,1,1] }\n",
                "at most one",
            ),
            ("[solver]\ndamping = 1.0\n", "damping"),
            ("[solver]\niterations = -3\n", "iterations"),
            ("[[constraints]]\ntype = \"position\"\nvertices = [1]\ntranslate = [1, 2]\n", "translate"),
        ] {
            let e = parse(&format!("[mesh]\npath = \"m.obj\"\n{body}")).unwrap_err().to_string();
            assert!(e.contains(needle), "{needle}: {e}");
        }
    }

    #[test]
    fn json_errors_name_the_key() {
        let json = |text: &str| {
            Scene::parse(text, SceneFormat::Json, Path::new("s.json"), PathBuf::new())
                .map(|_| ())
                .unwrap_err()
                .to_string()
        };
        for (text, words) in [
            (
                r#"{"mesh": {"path": "m.obj"}, "colliders": null}"#,
                "`colliders` must be a list of [[colliders]] tables, found null",
            ),
            (
                r#"{"mesh": {"path": "m.obj"}, "constraints": "x"}"#,
                "`constraints` must be a list of [[constraints]] tables, found a string",
            ),
            (r#"{"mesh": {"path": "m.obj"}, "contact": null}"#, "`contact` must be one [contact] table, found null"),
            (
                r#"{"mesh": {"path": "m.obj"}, "contact": [{}]}"#,
                "`contact` must be one [contact] table (not a list: [[contact]] or [...])",
            ),
            (
                r#"{"mesh": {"path": "m.obj"},
                 "contact": {"thickness": 1e400}}"#,
                "s.json: line 2, column 47: number out of range (in `contact.thickness`)",
            ),
            (
                r#"{"mesh": {"path": "m.obj"}, "contact": {"thickness": null}}"#,
                "invalid type: null, expected a number (in `contact.thickness`)",
            ),
            (r#"{"mesh": {"path": "m.obj"}, "solver": {"tolerance": "x"}}"#, "(in `solver.tolerance`)"),
            (
                r#"{"mesh": {"path": "m.o\"bj"}, "constraints": [{}, {"weight": 1e999}]}"#,
                "(in `constraints[1].weight`)",
            ),
        ] {
            let e = json(text);
            assert!(e.contains(words), "{text}: {e}");
            // Named once: no key after a message that names it (or its entry).
            assert!(!(e.contains("`contact` must") && e.contains("(in `")), "{text}: {e}");
        }
        let text = r#"{"a": [1, {"b\u0022": [0, 1e999"#;
        assert_eq!(json_key_at(text, text.len()), Some("a[1].b\"[1]".into()));
        assert_eq!(json_key_at(r#"{"a": 1}"#, 8), None);
    }

    #[test]
    fn json_has_the_same_schema() {
        let s = Scene::parse(
            r#"{"mesh": {"path": "m.obj", "normalize": false}, "constraints": [{"type": "iso_one_ring", "weight": 5}]}"#,
            SceneFormat::Json,
            Path::new("s.json"),
            PathBuf::new(),
        );
        let s = s.unwrap();
        assert!(!s.mesh.normalize);
        assert_eq!(s.groups[0].weight, 5.0);
        let e = Scene::parse(
            r#"{"mesh": {"path": "m.obj"}, "extra": 1}"#,
            SceneFormat::Json,
            Path::new("s.json"),
            PathBuf::new(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("extra"), "{e}");
    }
}
