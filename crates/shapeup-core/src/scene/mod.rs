//! Scene files: a mesh, solver settings and constraint groups, in TOML or JSON (same schema;
//! see `docs/scenes-and-cli.md`). Paths are relative to the scene file; unknown keys are errors that
//! name the key.
//!
//! [`Scene`] is the parsed file (what the CLI and the editor edit and save); [`Scene::load`]
//! reads its mesh and builds a ready-to-solve [`LoadedScene`].

mod build;
mod conflicts;
mod error;
pub mod frames;
mod generated;
mod parse;
mod run;
mod settings;
mod spec;
mod strict;
mod write;

pub use build::{
    DynamicSettingsError, LoadedScene, SpinningHandle, lumped_masses, other_elements, solve_static_with_contact,
};
pub use error::SceneError;
pub use generated::{GeneratedMesh, MAX_GENERATED_BYTES};
pub use parse::{SceneFormat, from_json_entry};
pub use run::{RunError, SceneSimulation, StepError, StepTotals, relative_changes};
pub use settings::{
    LoadSettings, MATERIAL_ITERATIONS, MATERIAL_TOLERANCE, MaterialSettings, MeshSettings, Mode, OutputSettings,
    SolverSettings, Units, WindSettings,
};
pub use spec::{GroupSpec, Rotate, SelectionSpec, SpecError, Spin, Targets, resolve_selection, unique_group_name};

use std::path::PathBuf;

/// A parsed scene file.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The `[mesh]` table.
    pub mesh: MeshSettings,
    /// The `[solver]` table.
    pub solver: SolverSettings,
    /// The constraint groups, in file order.
    pub groups: Vec<GroupSpec>,
    /// The `[[colliders]]` entries, in file order.
    pub colliders: Vec<crate::contact::ColliderSpec>,
    /// The `[contact]` table.
    pub contact: crate::contact::ContactSettings,
    /// The `[output]` table.
    pub output: OutputSettings,
    /// The `[material]` table, when given.
    pub material: Option<MaterialSettings>,
    /// The `[loads]` table (empty when not given).
    pub loads: LoadSettings,
    /// Directory that relative paths start from.
    pub base_dir: PathBuf,
    /// The scene file, for messages.
    pub file: PathBuf,
}

impl Scene {
    /// The mesh file's path, resolved against the scene's directory.
    pub fn mesh_path(&self) -> PathBuf {
        self.base_dir.join(&self.mesh.path)
    }

    /// `[mesh] start`, relative to the scene file's directory, when the scene has one.
    pub fn start_path(&self) -> Option<PathBuf> {
        self.mesh.start.as_ref().map(|p| self.base_dir.join(p))
    }

    /// The files a run of this scene reads, each with what it is: the scene file, its mesh
    /// (unless generated), every mesh collider's file. What no output may replace.
    pub fn input_files(&self) -> Vec<(PathBuf, String)> {
        let mut inputs: Vec<(PathBuf, String)> = vec![(self.file.clone(), "the scene file".into())];
        if self.mesh.generate.is_none() {
            inputs.push((self.mesh_path(), "the scene's mesh".into()));
        }
        if let Some(start) = self.start_path() {
            inputs.push((start, "the scene's start shape".into()));
        }
        for (i, c) in self.colliders.iter().enumerate() {
            if let crate::contact::ShapeSpec::Mesh { path, .. } = &c.shape {
                inputs.push((self.base_dir.join(path), format!("the mesh of colliders[{i}]")));
            }
        }
        inputs
    }

    /// The first of `outputs` that is one of the run's [`input_files`](Scene::input_files),
    /// however it is named (a link, `./`, `..`): a result written there would replace what the
    /// run reads. An output that does not exist yet is no input.
    pub fn input_replaced_by(&self, outputs: &[&std::path::Path]) -> Option<ReplacedInput> {
        let inputs = self.input_files();
        outputs.iter().find_map(|&output| {
            inputs.iter().find(|(input, _)| same_file::is_same_file(output, input).unwrap_or(false)).map(
                |(input, what)| ReplacedInput {
                    output: output.to_path_buf(),
                    input: input.clone(),
                    what: what.clone(),
                    frame: false,
                },
            )
        })
    }

    /// `[output] path`, resolved against the scene's directory.
    pub fn output_path(&self) -> Option<PathBuf> {
        self.output.path.as_ref().map(|p| self.base_dir.join(p))
    }

    /// `[output] report`, resolved against the scene's directory.
    pub fn report_path(&self) -> Option<PathBuf> {
        self.output.report.as_ref().map(|p| self.base_dir.join(p))
    }
}

/// An output of a run that is one of its inputs ([`Scene::input_replaced_by`], a frame:
/// [`frames::frame_replacing_input`]), refused before any work: the one message every door
/// (command line, Python) gives.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "{}: is {what} ({}); shapeup never replaces its inputs, {}",
    crate::io::one_line(output.display()),
    crate::io::one_line(input.display()),
    if *frame { "simulate into another folder" } else { "write the result elsewhere" }
)]
pub struct ReplacedInput {
    /// The output (a frame's path for a frame).
    pub output: PathBuf,
    /// The input it is, as the scene names it.
    pub input: PathBuf,
    /// What that input is ("the scene's mesh", …).
    pub what: String,
    /// Whether the output is a frame of `simulate`.
    pub frame: bool,
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use std::path::Path;

    /// A report's `max_violation` is scale-free for every type: a 10 % stretch is a strain
    /// violation of 0.1 and a bent cloth the same bending violation at 1 m and at 10 m (the
    /// violation was a strain over the mean edge length: 0.88 and 0.088 here).
    #[test]
    fn the_reported_violation_is_the_same_at_every_size() {
        let at = |size: f64| {
            let text = format!(
                "[mesh]\ngenerate = {{ kind = \"cloth\", vertices = [11, 11], size = [{size}, {size}] }}\nnormalize = false\n\
                 [[constraints]]\ntype = \"triangle_strain\"\n[[constraints]]\ntype = \"bending\"\n"
            );
            let scene = Scene::parse(&text, SceneFormat::Toml, Path::new("s.toml"), PathBuf::new()).unwrap();
            let loaded = scene.load().unwrap();
            let mean_edge = crate::geometry::mean_edge_length(&loaded.rest);
            // Stretched 10 % along x, then rolled onto a cylinder of radius 2 sizes (no stretch
            // across the roll: the arc length along z is kept).
            let rest = loaded.rest_positions();
            let stretched: Vec<DVec3> = rest.iter().map(|p| DVec3::new(1.1 * p.x, p.y, p.z)).collect();
            let r = 2.0 * size;
            let rolled: Vec<DVec3> =
                rest.iter().map(|p| DVec3::new(p.x, p.y + r - r * (p.z / r).cos(), r * (p.z / r).sin())).collect();
            let group = |k: usize| loaded.system.group(loaded.group_ids[k]).unwrap();
            (group(0).relative_violation(&stretched, mean_edge), group(1).relative_violation(&rolled, mean_edge))
        };
        let ((strain_1, bending_1), (strain_10, bending_10)) = (at(1.0), at(10.0));
        assert!((strain_1 - 0.1).abs() < 1e-9 && (strain_10 - 0.1).abs() < 1e-9, "{strain_1} {strain_10}");
        assert!(bending_1 > 1e-3, "the roll bends: {bending_1}");
        assert!((bending_1 - bending_10).abs() < 1e-9 * bending_1, "{bending_1} {bending_10}");
    }

    /// A piece held only by a position group of weight 0 is said to be so (it read as having
    /// no position constraint at all).
    #[test]
    fn a_handle_of_weight_zero_is_named_as_the_reason_a_piece_is_free() {
        let text = |weight: f64| {
            format!(
                "[mesh]\ngenerate = {{ kind = \"cloth\", vertices = [4, 4], size = [1.0, 1.0] }}\n\
                 [[constraints]]\ntype = \"edge_spring\"\n[[constraints]]\ntype = \"position\"\nvertices = [0]\nweight = {weight:?}\n"
            )
        };
        let solve = |weight: f64| {
            let scene = Scene::parse(&text(weight), SceneFormat::Toml, Path::new("s.toml"), PathBuf::new()).unwrap();
            scene.load().and_then(|mut loaded| loaded.solve_static(Some(1)).map(|_| ()))
        };
        let message = solve(0.0).unwrap_err().to_string();
        assert!(message.contains("of weight > 0 (those it has weigh 0)"), "{message}");
        assert!(message.contains("give its position group a weight > 0"), "{message}");
        assert!(solve(1.0).is_ok());
    }

    /// An output is refused when it is an input under any name (`./`, `..`, a link), and only
    /// then: a new file, or an existing one that is no input, is fine.
    #[test]
    fn an_output_naming_an_input_under_any_name_is_found() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("sub")).unwrap();
        std::fs::write(d.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        std::fs::write(d.join("other.obj"), "").unwrap();
        let text = "[mesh]\npath = \"tri.obj\"\n[[constraints]]\ntype = \"edge_spring\"\n";
        let file = d.join("s.toml");
        std::fs::write(&file, text).unwrap();
        let scene = Scene::parse(text, SceneFormat::Toml, &file, d.to_path_buf()).unwrap();
        let dotted = d.join("sub").join("..").join("tri.obj");
        let new = d.join("new.obj");
        let ReplacedInput { output, input, what, .. } = scene.input_replaced_by(&[&new, &dotted]).unwrap();
        assert_eq!(
            (output.as_path(), input.as_path(), what.as_str()),
            (dotted.as_path(), d.join("tri.obj").as_path(), "the scene's mesh")
        );
        let what = scene.input_replaced_by(&[&d.join(".").join("s.toml")]).unwrap().what;
        assert_eq!(what, "the scene file");
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(d.join("tri.obj"), d.join("link.obj")).unwrap();
            assert!(scene.input_replaced_by(&[&d.join("link.obj")]).is_some(), "a link to the mesh");
        }
        assert!(scene.input_replaced_by(&[&d.join("new.obj"), &d.join("other.obj")]).is_none());
    }
}
