//! Scene files: a mesh, solver settings and constraint groups, in TOML or JSON (same schema;
//! see `docs/scenes-and-cli.md`). Paths are relative to the scene file; unknown keys are errors that
//! name the key.
//!
//! [`Scene`] is the parsed file (what the CLI and the editor edit and save); [`Scene::load`]
//! reads its mesh and builds a ready-to-solve [`LoadedScene`].

mod build;
mod error;
pub mod frames;
mod generated;
mod parse;
mod run;
mod settings;
mod spec;
mod strict;
mod write;

pub use build::{DynamicSettingsError, LoadedScene, SpinningHandle, lumped_masses, solve_static_with_contact};
pub use error::SceneError;
pub use generated::{GeneratedMesh, MAX_GENERATED_BYTES};
pub use parse::SceneFormat;
pub use run::{RunError, SceneSimulation, StepError, StepTotals, relative_changes};
pub use settings::{MeshSettings, Mode, OutputSettings, SolverSettings};
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

    /// The files a run of this scene reads, each with what it is: the scene file, its mesh
    /// (unless generated), every mesh collider's file. What no output may replace.
    pub fn input_files(&self) -> Vec<(PathBuf, String)> {
        let mut inputs: Vec<(PathBuf, String)> = vec![(self.file.clone(), "the scene file".into())];
        if self.mesh.generate.is_none() {
            inputs.push((self.mesh_path(), "the scene's mesh".into()));
        }
        for (i, c) in self.colliders.iter().enumerate() {
            if let crate::contact::ShapeSpec::Mesh { path, .. } = &c.shape {
                inputs.push((self.base_dir.join(path), format!("the mesh of colliders[{i}]")));
            }
        }
        inputs
    }

    /// The first of `outputs` that is one of the run's [`input_files`](Scene::input_files),
    /// however it is named (a link, `./`, `..`), with that input and what it is: a result
    /// written there would replace what the run reads. An output that does not exist yet is no
    /// input.
    pub fn input_replaced_by<'a>(
        &self,
        outputs: &[&'a std::path::Path],
    ) -> Option<(&'a std::path::Path, PathBuf, String)> {
        let inputs = self.input_files();
        outputs.iter().find_map(|&output| {
            inputs
                .iter()
                .find(|(input, _)| same_file::is_same_file(output, input).unwrap_or(false))
                .map(|(input, what)| (output, input.clone(), what.clone()))
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

#[cfg(test)]
mod tests {
    use super::*;

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
        let (output, input, what) = scene.input_replaced_by(&[&new, &dotted]).unwrap();
        assert_eq!(
            (output, input.as_path(), what.as_str()),
            (dotted.as_path(), d.join("tri.obj").as_path(), "the scene's mesh")
        );
        let (_, _, what) = scene.input_replaced_by(&[&d.join(".").join("s.toml")]).unwrap();
        assert_eq!(what, "the scene file");
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(d.join("tri.obj"), d.join("link.obj")).unwrap();
            assert!(scene.input_replaced_by(&[&d.join("link.obj")]).is_some(), "a link to the mesh");
        }
        assert!(scene.input_replaced_by(&[&d.join("new.obj"), &d.join("other.obj")]).is_none());
    }
}
