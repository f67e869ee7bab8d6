//! From a parsed [`Scene`] to a solvable system: load the mesh, map it to the working frame,
//! resolve selections and build each group.

use super::{Scene, SceneError, SolverSettings};
use crate::constraints::{attach_degenerate_vertices, held_vertices};
use crate::contact::{ContactModel, ContactParams, Shape, ShapeSpec};
use crate::dynamics::{DynamicsParams, ParamError, Simulation};
use crate::geometry::{RestGeometry, WorkingFrame, lumped_masses_surface, lumped_masses_volume};
use crate::io::{Attributes, read_mesh};
use crate::mesh::Mesh;
use crate::solver::{ConstraintGroup, GroupId, SolveError, SolveReport, SolverParams, System};
use crate::warnings::Warnings;
use glam::DVec3;
use std::time::Instant;

/// A scene with its mesh loaded and its constraints built: ready to solve.
#[derive(Debug)]
pub struct LoadedScene {
    /// The parsed scene.
    pub scene: Scene,
    /// The mesh as read (input frame); after `tetrahedralize`, with TetGen's points after the
    /// input's vertices.
    pub mesh: Mesh,
    /// What the mesh file carried besides positions and faces, which outputs write back
    /// ([`Attributes::None`] for a mesh [`Scene::build`] was given).
    pub attributes: Attributes,
    /// Vertices of the input mesh (before tetrahedralization added points): what outputs write.
    pub input_vertices: usize,
    /// What loading changed (polygons triangulated, faces left out…), each naming the file;
    /// a static solve adds the collider motion it ignores.
    pub warnings: Warnings,
    /// Input ↔ working frame.
    pub frame: WorkingFrame,
    /// Rest geometry in the working frame.
    pub rest: RestGeometry,
    /// The constraint system.
    pub system: System,
    /// The system's id of each scene group, in scene order.
    pub group_ids: Vec<GroupId>,
    /// Seconds to read the mesh.
    pub load_seconds: f64,
    /// Seconds to build rest geometry and constraints.
    pub build_seconds: f64,
    /// The colliders and self-collision (`None` when the scene has neither).
    pub contact: Option<ContactModel>,
    /// `[mesh] start`'s positions (input frame), which solves start from instead of the rest
    /// shape ([`LoadedScene::start_positions`]); `None` without the key, or for a scene
    /// [`Scene::build`] was given a mesh for.
    pub start: Option<Vec<DVec3>>,
}

impl Scene {
    /// Reads the mesh and builds every group.
    ///
    /// # Errors
    /// [`SceneError`] naming the scene file and the entry (bad selection, option, mesh file…).
    pub fn load(&self) -> Result<LoadedScene, SceneError> {
        let t = Instant::now();
        let loaded = self.read_mesh()?;
        let load_seconds = t.elapsed().as_secs_f64();
        let scene = self.with_physical_groups(loaded.attributes.physical_groups())?;
        let start = self.read_start(&loaded.mesh)?;
        let mut built = scene.build_from(loaded.mesh, start, loaded.warnings, load_seconds)?;
        built.attributes = loaded.attributes;
        Ok(built)
    }

    /// The positions of `[mesh] start` (input frame), checked against the scene's `mesh` as
    /// read (before tetrahedralization); `None` without the key.
    ///
    /// # Errors
    /// [`SceneError::Start`] for a file that cannot be read; [`SceneError::Invalid`] naming
    /// `[mesh] start` for another vertex count, other faces, an empty path, or a
    /// tetrahedralized scene (TetGen's inner points have no start).
    pub fn read_start(&self, mesh: &Mesh) -> Result<Option<Vec<DVec3>>, SceneError> {
        let Some(path) = self.start_path() else { return Ok(None) };
        let input_vertices = mesh.num_vertices();
        let invalid =
            |message: String| SceneError::Invalid { path: self.file.clone(), entry: "[mesh] start".into(), message };
        if self.mesh.tetrahedralize && mesh.tetrahedra.is_empty() {
            return Err(invalid(
                "a start shape cannot be used with tetrahedralize = true (the points TetGen adds have none)".into(),
            ));
        }
        if self.mesh.start.as_ref().is_some_and(|p| p.as_os_str().is_empty()) {
            return Err(invalid("is empty: name a mesh file of the scene's vertices, or leave the key out".into()));
        }
        let start = read_mesh(&path).map_err(|source| SceneError::Start { path: self.file.clone(), source })?.mesh;
        let mesh_name = match self.mesh.generate {
            Some(_) => "the generated mesh".to_string(),
            None => format!("the mesh {}", self.mesh_path().display()),
        };
        if start.num_vertices() != input_vertices {
            return Err(invalid(format!(
                "{} has {} vertices where {mesh_name} has {input_vertices}: a start shape moves the mesh's own vertices, in their order",
                path.display(),
                start.num_vertices(),
            )));
        }
        // Same count, other order: an STL file's vertices are merged in the order its
        // triangles first use them, so they would land on other vertices. Faces are compared
        // as sets of vertex sets (their order, first corner and orientation may differ).
        if let Some(why) = other_elements(mesh, &start) {
            return Err(invalid(format!(
                "{} is not a shape of {mesh_name}'s vertices in their order: {why} (a start shape has the mesh's faces; STL merges vertices and reorders them)",
                path.display(),
            )));
        }
        Ok(Some(start.positions))
    }

    /// The scene with each `physical = "NAME"` selection replaced by the vertices of the mesh's
    /// physical group ([`SelectionSpec::with_physical_groups`]).
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming the entry: no physical group of that name (listing the
    /// mesh's), or one without vertices.
    fn with_physical_groups(&self, groups: &[crate::io::PhysicalGroup]) -> Result<Scene, SceneError> {
        let mut scene = self.clone();
        let mesh = self.mesh_path();
        for (i, spec) in scene.groups.iter_mut().enumerate() {
            spec.selection = spec.selection.with_physical_groups(groups, &mesh).map_err(|e| SceneError::Invalid {
                path: self.file.clone(),
                entry: format!("constraints[{i}] (\"{}\")", spec.name),
                message: e.to_string(),
            })?;
        }
        Ok(scene)
    }

    /// The scene's mesh: read from its file, or generated.
    ///
    /// # Errors
    /// [`SceneError::Mesh`] naming the scene and the mesh file's problem;
    /// [`SceneError::Invalid`] for a generated mesh past [`super::MAX_GENERATED_BYTES`].
    pub fn read_mesh(&self) -> Result<crate::io::LoadedMesh, SceneError> {
        match &self.mesh.generate {
            Some(generated) => {
                // Checked again here: a scene edited after parsing (the editor, overrides) may
                // ask for more than the cap.
                generated.validate().map_err(|e| SceneError::Invalid {
                    path: self.file.clone(),
                    entry: "[mesh]".into(),
                    message: e.to_string(),
                })?;
                Ok(crate::io::LoadedMesh {
                    mesh: generated.mesh(),
                    attributes: Attributes::None,
                    warnings: Warnings::new(),
                })
            }
            None => read_mesh(&self.mesh_path()).map_err(|source| SceneError::Mesh { path: self.file.clone(), source }),
        }
    }

    /// Builds the scene's groups on an already loaded mesh (without `[mesh] start`, which
    /// [`Scene::load`] reads).
    ///
    /// # Errors
    /// As [`Scene::load`], but for the mesh file itself.
    pub fn build(&self, mesh: Mesh, warnings: Warnings, load_seconds: f64) -> Result<LoadedScene, SceneError> {
        self.build_from(mesh, None, warnings, load_seconds)
    }

    /// [`Scene::build`] with the start shape's positions (input frame), which contact's checks
    /// at time 0 look at and solves start from.
    fn build_from(
        &self,
        mesh: Mesh,
        start: Option<Vec<DVec3>>,
        mut warnings: Warnings,
        load_seconds: f64,
    ) -> Result<LoadedScene, SceneError> {
        let t = Instant::now();
        let invalid = |entry: &str, message: String| SceneError::Invalid {
            path: self.file.clone(),
            entry: entry.into(),
            message,
        };
        let input_vertices = mesh.num_vertices();
        let mesh = if self.mesh.tetrahedralize && mesh.tetrahedra.is_empty() {
            fill_with_tetrahedra(&mesh).map_err(|e| invalid("[mesh]", e.to_string()))?
        } else {
            mesh
        };
        if mesh.triangles.is_empty() && mesh.tetrahedra.is_empty() {
            return Err(invalid(
                "[mesh]",
                format!("{} has no faces{}", self.mesh_path().display(), mesh.why_no_triangles()),
            ));
        }
        let material = self.material()?;
        let frame = self.working_frame(&mesh.positions, material.is_some());
        let working: Vec<DVec3> = mesh.positions.iter().map(|&p| frame.to_working(p)).collect();
        let rest = RestGeometry::of_mesh(working, &mesh);
        let mut system = System::new(mesh.num_vertices(), self.solver.solver_params());
        let mut group_ids = Vec::with_capacity(self.groups.len());
        for (i, spec) in self.groups.iter().enumerate() {
            let entry = format!("constraints[{i}] (\"{}\")", spec.name);
            let group = spec.build(&mesh, &rest, &frame).map_err(|e| invalid(&entry, e.to_string()))?;
            group_ids.push(system.add_group(group).map_err(|e| invalid(&entry, e.to_string()))?);
        }
        if let Some(material) = &material {
            if !self.colliders.is_empty() || self.contact.self_collision {
                return Err(invalid(
                    "[material]",
                    "colliders and self-collision do not work with a material yet: contact iterates plain \
                     local-global steps, which a material's energy needs a line search for; leave out [material] \
                     or the contact"
                        .into(),
                ));
            }
            let (groups, flat) =
                self.material_groups(&rest, material).map_err(|e| invalid("[material]", e.to_string()))?;
            for group in groups {
                system.add_group(group).map_err(|e| invalid("[material]", e.to_string()))?;
            }
            if material.thickness.is_some() {
                warnings.add_many(
                    "degenerate_triangles_without_material",
                    "degenerate triangles (rest area at most 1e-12 of their longest edge squared) carry no material",
                    flat.len(),
                    || flat.first().map(|t| format!("triangle {t}")).unwrap_or_default(),
                );
            } else {
                warnings.add_many(
                    "flat_tetrahedra_without_material",
                    "flat tetrahedra (rest volume at most 1e-12 of their longest edge cubed) carry no material",
                    flat.len(),
                    || flat.first().map(|t| format!("tetrahedron {t}")).unwrap_or_default(),
                );
            }
        }
        if let Some(pressure) = self.loads.pressure {
            if !pressure.is_finite() {
                return Err(invalid(
                    "[loads]",
                    format!("pressure must be a finite number (pascals), found {pressure}"),
                ));
            }
            if !self.colliders.is_empty() || self.contact.self_collision {
                return Err(invalid(
                    "[loads]",
                    "colliders and self-collision do not work with a pressure yet: contact iterates plain local-global \
                     steps, which a pressure's energy needs a line search for; leave out the pressure or the contact"
                        .into(),
                ));
            }
            let group =
                crate::materials::pressure_group(&rest, frame.pressure_to_working(pressure), 1.0).ok_or_else(|| {
                    invalid("[loads]", "a pressure acts on a surface's triangles, and the mesh has none".into())
                })?;
            system.add_group(group).map_err(|e| invalid("[loads]", e.to_string()))?;
        }
        if let Some(wind) = &self.loads.wind {
            wind.wind().map_err(|message| invalid("[loads]", message))?;
            if material.is_none() {
                return Err(invalid(
                    "[loads]",
                    "wind needs a [material]: its force, ½ ρ C A u², is in newtons on masses in kg".into(),
                ));
            }
            if rest.triangles.is_empty() {
                return Err(invalid("[loads]", "wind acts on a surface's triangles, and the mesh has none".into()));
            }
        }
        // Vertices that only zero-area triangles use follow their edge (math reference, "Edge cases").
        let (group, attached, stranded) = attach_degenerate_vertices(&rest, system.groups().map(|(_, g)| g));
        if let Some(group) = group {
            system.add_group(group).map_err(|e| invalid("[mesh]", e.to_string()))?;
        }
        warnings.add_many(
            "degenerate_vertices_attached",
            "vertices that only degenerate (zero-area) triangles use, attached to their edge",
            attached.len(),
            || attached.first().map(|v| format!("vertex {v}")).unwrap_or_default(),
        );
        warnings.add_many(
            "degenerate_vertices_stranded",
            "vertices that only degenerate (zero-area) triangles use and no constraint reaches, kept at their rest position",
            stranded.len(),
            || stranded.first().map(|v| format!("vertex {v}")).unwrap_or_default(),
        );
        let start_working = start.as_ref().map(|s| s.iter().map(|&p| frame.to_working(p)).collect::<Vec<_>>());
        let contact = self.build_contact(&mesh, &rest, start_working.as_deref(), &frame, &mut warnings)?;
        if let Some(model) = &contact {
            let inside = pins_inside_colliders(&system, model);
            warnings.add_many(
                "pin_inside_collider",
                "pinned vertices are held at a point inside a collider: contact cannot move them out (a hard pin keeps \
                 them there, a soft one pulls them back in against it); move the pin or the collider",
                inside.len(),
                || inside.first().map(|(v, group)| format!("vertex {v}, group \"{group}\"")).unwrap_or_default(),
            );
        }
        // Name the mesh file (or, for a generated mesh, the scene) in what building found.
        let source = if self.mesh.generate.is_some() { self.file.clone() } else { self.mesh_path() };
        let mut warnings = warnings.for_file(&source);
        // Groups at odds with each other are the scene's.
        let mut found = Warnings::new();
        super::conflicts::warn_of_conflicts(&system, &self.groups, &mesh, &rest.positions, &mut found);
        warnings.extend(found.for_file(&self.file));
        Ok(LoadedScene {
            scene: self.clone(),
            mesh,
            attributes: Attributes::None,
            input_vertices,
            warnings,
            frame,
            rest,
            system,
            group_ids,
            load_seconds,
            build_seconds: t.elapsed().as_secs_f64(),
            contact,
            start,
        })
    }

    /// The frame the solver works in: with a material, metres ([`super::Units`]: x_work = x · metres
    /// per unit, so that moduli, densities and gravity are physical); otherwise the normalized
    /// frame when `[mesh] normalize` (the default), else the input's.
    pub fn working_frame(&self, positions: &[DVec3], material: bool) -> WorkingFrame {
        if material {
            WorkingFrame::metres(self.mesh.units.unwrap_or_default().metres())
        } else if self.mesh.normalize {
            WorkingFrame::fit(positions)
        } else {
            WorkingFrame::IDENTITY
        }
    }

    /// A material's groups on `rest` (metres), as a static solve takes them: its hyperelastic
    /// energy on every tetrahedron (multiplier 1), and its self-weight, the loads m_v g of the
    /// lumped masses (ρ |V_T|/4 per corner) under `[solver] gravity` (m/s²), so that a static
    /// solve is the simulation's equilibrium. [`LoadedScene::start_simulation`] turns them into
    /// the dynamic mode's (whatever the scene's mode: `simulate` of a static scene too). Also
    /// the flat tetrahedra that carry no material.
    fn material_groups(
        &self,
        rest: &RestGeometry,
        material: &crate::materials::Material,
    ) -> Result<(Vec<ConstraintGroup>, Vec<usize>), crate::materials::MaterialError> {
        let (group, flat) = crate::materials::material_group(rest, material, 1.0)?;
        let mut groups = vec![group];
        let gravity = DVec3::from_array(self.solver.gravity);
        if gravity != DVec3::ZERO {
            let weights: Vec<Box<dyn crate::constraints::Constraint>> = material_masses(rest, material)
                .iter()
                .enumerate()
                .filter(|(_, m)| **m > 0.0)
                .map(|(v, &m)| {
                    Box::new(crate::constraints::Force::new(v as u32, gravity * m, rest.positions[v]))
                        as Box<dyn crate::constraints::Constraint>
                })
                .collect();
            groups.push(ConstraintGroup::new(SELF_WEIGHT_GROUP, 1.0, weights));
        }
        Ok((groups, flat))
    }

    /// The scene's colliders and `[contact]` settings as a [`ContactModel`] (`None` when there
    /// are no colliders and no self-collision). Counts, as one warning, the rest shape's
    /// vertices that start inside a collider or within the thickness of it.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming `colliders[i]`: a mesh that cannot be read, has no faces
    /// or is said to be closed while open; naming `[contact]`: a self-collision thickness over
    /// the mean edge length ([`crate::contact::ContactSettings::resolve_thickness`]).
    pub fn build_contact(
        &self,
        mesh: &Mesh,
        rest: &RestGeometry,
        start: Option<&[DVec3]>,
        frame: &WorkingFrame,
        warnings: &mut Warnings,
    ) -> Result<Option<ContactModel>, SceneError> {
        // Checked where the run starts: the start shape when there is one.
        let (at_start, shape) = match start {
            Some(start) => (start, "start shape ([mesh] start)"),
            None => (&rest.positions[..], "rest shape"),
        };
        if self.colliders.is_empty() && !self.contact.self_collision {
            return Ok(None);
        }
        let (edge, size) = (crate::geometry::mean_edge_length(rest), crate::geometry::bounding_box_diagonal(rest));
        let thickness = self.contact.resolve_thickness(frame.scale, edge, size).map_err(|e| SceneError::Invalid {
            path: self.file.clone(),
            entry: "[contact]".into(),
            message: e.to_string(),
        })?;
        let colliders = self
            .colliders
            .iter()
            .enumerate()
            .map(|(i, c)| {
                c.build(frame, &self.base_dir, thickness).map_err(|e| SceneError::Invalid {
                    path: self.file.clone(),
                    entry: format!("colliders[{i}]"),
                    message: e.to_string(),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        // Named by the collider's own file: the warnings without one name the scene's mesh.
        for (i, (spec, collider)) in self.colliders.iter().zip(&colliders).enumerate() {
            if let (ShapeSpec::Mesh { path, .. }, Shape::Mesh(shape)) = (&spec.shape, &collider.shape) {
                let degenerate = shape.degenerate_triangles();
                let mut found = Warnings::new();
                found.add_many(
                    "degenerate_collider_triangles",
                    "zero-area (degenerate) triangles in a mesh collider: they have no normal of their own",
                    degenerate.len(),
                    || degenerate.first().map(|t| format!("colliders[{i}], triangle {t} (from 0)")).unwrap_or_default(),
                );
                warnings.extend(found.for_file(&self.base_dir.join(path)));
            }
        }
        // Vertices in an element take part; the others keep their positions.
        let mut active = vec![false; mesh.num_vertices()];
        for v in mesh.triangles.iter().flatten().chain(mesh.tetrahedra.iter().flatten()) {
            active[*v as usize] = true;
        }
        let overlapping: Vec<usize> = (0..at_start.len())
            .filter(|&v| active[v] && colliders.iter().any(|c| c.closest_at(at_start[v], 0.0).distance < thickness))
            .collect();
        warnings.add_many(
            "collider_overlaps_rest_shape",
            &format!("vertices of the {shape} start inside a collider or closer than the contact thickness (they are pushed out: at a simulation's start, by a static solve's iterations; a hard pin keeps its vertices where it holds them)"),
            overlapping.len(),
            || overlapping.first().map(|v| format!("vertex {v}")).unwrap_or_default(),
        );
        let surface = if mesh.tetrahedra.is_empty() {
            mesh.triangles.clone()
        } else {
            crate::topology::tetrahedron_boundary(&mesh.tetrahedra)
        };
        let params =
            ContactParams { thickness, friction: self.contact.friction, self_collision: self.contact.self_collision };
        let mut model = ContactModel::new(colliders, params, &surface, active);
        let close = model.self_pairs_at_rest(at_start);
        warnings.add_many(
            "self_contact_at_rest",
            &format!("pairs of the {shape} (a vertex and a triangle, or two edges, not neighbours) are closer than the self-collision thickness: they start in contact and push apart (give [contact] a thickness well under the mean edge length)"),
            close,
            || {
                format!(
                    "thickness {}, mean edge length {} (input units)",
                    crate::text::number(thickness / frame.scale),
                    crate::text::number(crate::geometry::mean_edge_length(rest) / frame.scale)
                )
            },
        );
        let (caught, first) = model.self_intersections_at_rest(at_start);
        warnings.add_many(
            "self_intersection_at_rest",
            &format!(
                "pairs of an edge and a triangle of the {shape} (not neighbours) pass through or touch each other: \
                 self-collision keeps every pair on the side it starts on, so the surface stays caught in itself \
                 (separate its parts in the input)"
            ),
            caught,
            || {
                first.map_or_else(String::new, |(e, t)| {
                    format!("edge ({}, {}) and triangle ({}, {}, {}), vertices from 0", e[0], e[1], t[0], t[1], t[2])
                })
            },
        );
        Ok(Some(model))
    }
}

/// Why `other`'s elements are not `mesh`'s, if they are not: faces compared as sets of vertex
/// sets (order, first corner and orientation free), then tetrahedra likewise. What tells a
/// shape of a mesh's own vertices (a `[mesh] start`, `shapeup energy`'s positions) from a
/// file whose vertices were merged or reordered (STL).
pub fn other_elements(mesh: &Mesh, other: &Mesh) -> Option<String> {
    fn canonical<'a>(elements: impl Iterator<Item = &'a [u32]>) -> Vec<Vec<u32>> {
        let mut all: Vec<Vec<u32>> = elements
            .map(|e| {
                let mut e = e.to_vec();
                e.sort_unstable();
                e
            })
            .collect();
        all.sort_unstable();
        all
    }
    let faces = |m: &Mesh| canonical((0..m.polygons.len()).filter_map(|i| m.polygons.get(i)));
    let tets = |m: &Mesh| canonical(m.tetrahedra.iter().map(|t| &t[..]));
    for (what, ours, theirs) in [("faces", faces(mesh), faces(other)), ("tetrahedra", tets(mesh), tets(other))] {
        if ours.len() != theirs.len() {
            return Some(format!("it has {} {what} where the mesh has {}", theirs.len(), ours.len()));
        }
        if let Some(missing) = ours.iter().find(|e| theirs.binary_search(e).is_err()) {
            return Some(format!("the mesh's {what} on vertices {missing:?} (from 0) are not among its {what}"));
        }
    }
    None
}

/// The vertices that a group's constraints hold at a point ([`crate::constraints::Constraint::held_points`]:
/// position handles, hard or of a weight above 0) inside one of `model`'s colliders (as placed
/// at time 0), each once with the first group that holds it there, in group and constraint order.
fn pins_inside_colliders(system: &System, model: &ContactModel) -> Vec<(u32, String)> {
    let mut inside = Vec::new();
    let mut seen = std::collections::HashSet::new();
    // A soft group of weight 0 pulls nothing.
    for (_, group) in system.groups().filter(|(_, g)| g.hard || g.multiplier > 0.0) {
        for (vertices, targets) in group.constraints.iter().filter_map(|c| c.held_points()) {
            for (&v, &target) in vertices.iter().zip(targets) {
                if model.colliders().iter().any(|c| c.closest_at(target, 0.0).distance < 0.0) && seen.insert(v) {
                    inside.push((v, group.name.clone()));
                }
            }
        }
    }
    inside
}

/// Iterations of a static solve between two contact detections: a handle drags the surface
/// over many iterations, so what touches is found again from where it has got to.
const STATIC_CONTACT_CHUNK: usize = 10;

/// Name of the group of a material's self-weight in static mode.
pub const SELF_WEIGHT_GROUP: &str = "self-weight";

/// A static solve with contact: chunks of [`STATIC_CONTACT_CHUNK`] iterations of
/// [`crate::contact::solve_with_contact`], each detecting from where the last left the
/// surface (its motion extrapolated) and ending with the contact projection. E after each
/// iteration is recorded and passed to `after_iteration` (which may stop the solve). The
/// contact weights are set relative to the static matrix's diagonal when `system` has none
/// (clear them, [`System::set_contact_weights`] with `None`, after changing the groups or
/// the model). What [`LoadedScene::solve_static`] runs for a scene with contact, and Python's
/// `Solver` for one with colliders.
///
/// # Errors
/// As [`System::solve_with`].
pub fn solve_static_with_contact(
    system: &mut System,
    contact: &mut ContactModel,
    q: &mut [DVec3],
    iterations: usize,
    mut after_iteration: impl FnMut(usize, f64) -> std::ops::ControlFlow<()>,
) -> Result<SolveReport, SolveError> {
    // E must be finite, as the solve without contact requires (an overflowing target would
    // otherwise be written with null energies and exit 0).
    let mut report = SolveReport::default();
    report.initial_energy = system.finite_energy(q)?;
    if system.contact_weights().is_none() {
        // W relative to each vertex's diagonal entry of the static matrix, in its first
        // factorization.
        let weights = contact.weights(&system.diagonal_without_contact()?);
        system.set_contact_weights(Some(weights))?;
        // Factored now, as a solve without contact is, even for 0 iterations.
        system.prepare()?;
    }
    let mut previous = q.to_vec();
    // A vertex a hard group holds must not move: inverse mass 0 (the mask once assembled).
    let movable =
        |system: &System| -> Vec<f64> { system.held_mask().iter().map(|&held| if held { 0.0 } else { 1.0 }).collect() };
    let mut inverse_mass = movable(system);
    let mut done = 0;
    'chunks: while done < iterations {
        let chunk = STATIC_CONTACT_CHUNK.min(iterations - done);
        let predicted: Vec<DVec3> = q.iter().zip(&previous).map(|(&x, &p)| x + (x - p)).collect();
        previous.copy_from_slice(q);
        contact.begin_step(q, &predicted, 0.0, 0.0);
        for k in 0..chunk {
            let part = crate::contact::solve_with_contact(system, contact, q, 1)?;
            if done == 0 {
                inverse_mass = movable(system);
            }
            report.local_seconds += part.local_seconds;
            report.global_seconds += part.global_seconds;
            report.setup_seconds += part.setup_seconds;
            if k + 1 == chunk {
                contact.finish_step(q, &inverse_mass);
            }
            done += 1;
            let energy = system.finite_energy(q)?;
            report.energies.push(energy);
            if after_iteration(done, energy).is_break() {
                contact.finish_step(q, &inverse_mass);
                break 'chunks;
            }
        }
    }
    Ok(report)
}

/// Why `tetrahedralize = true` failed.
#[derive(Debug, thiserror::Error)]
enum FillError {
    /// TetGen refused the surface.
    #[cfg(feature = "tetgen")]
    #[error(transparent)]
    TetGen(#[from] crate::tetrahedralize::TetrahedralizeError),
    /// This build has no TetGen.
    #[cfg(not(feature = "tetgen"))]
    #[error(
        "tetrahedralize = true needs TetGen, which this build leaves out (it is AGPL-3.0): build shapeup with \
         `--features tetgen`, or give a tetrahedral mesh (.msh, .node/.ele)"
    )]
    NoTetGen,
}

/// `tetrahedralize = true`: TetGen when built with the `tetgen` feature.
#[cfg(feature = "tetgen")]
fn fill_with_tetrahedra(mesh: &Mesh) -> Result<Mesh, FillError> {
    Ok(crate::tetrahedralize::tetrahedralize(mesh, None)?)
}

#[cfg(not(feature = "tetgen"))]
fn fill_with_tetrahedra(_mesh: &Mesh) -> Result<Mesh, FillError> {
    Err(FillError::NoTetGen)
}

/// A material's lumped masses (kg, `rest` in metres): for a solid m_i = ρ Σ_{T ∋ i} |V_T| / 4,
/// for a shell of thickness h m_i = ρ h Σ_{t ∋ i} A_t / 3, exactly (no floor: a part in
/// millimetres has vertex masses of 1e-14 kg, which the 1e-9 floor of [`lumped_masses`] would
/// multiply), 0 for a vertex in no element.
pub fn material_masses(rest: &RestGeometry, material: &crate::materials::Material) -> Vec<f64> {
    let density = material.density;
    let mut masses = vec![0.0; rest.num_vertices()];
    if let Some(h) = material.thickness {
        for (t, &area) in rest.triangles.iter().zip(&rest.triangle_areas) {
            for &v in t {
                masses[v as usize] += density * h * area / 3.0;
            }
        }
        return masses;
    }
    for t in &rest.tetrahedra {
        let p = t.map(|v| rest.positions[v as usize]);
        let share = density * crate::geometry::tet_volume(p[0], p[1], p[2], p[3]).abs() / 4.0;
        for &v in t {
            masses[v as usize] += share;
        }
    }
    masses
}

/// Lumped masses m_i of `rest` (working frame): ρ Σ|V_T|/4 on a tetrahedral mesh, else
/// ρ Σ A_t/3 (floored at 1e-9); 0 for a vertex in no element, which is not simulated and keeps
/// its position (as in static mode).
pub fn lumped_masses(rest: &RestGeometry, density: f64) -> Vec<f64> {
    let mut in_element = vec![false; rest.num_vertices()];
    let mut masses = if rest.tetrahedra.is_empty() {
        rest.triangles.iter().flatten().for_each(|&v| in_element[v as usize] = true);
        lumped_masses_surface(rest.num_vertices(), &rest.triangles, &rest.triangle_areas, density)
    } else {
        rest.tetrahedra.iter().flatten().for_each(|&v| in_element[v as usize] = true);
        lumped_masses_volume(&rest.positions, &rest.tetrahedra, density)
    };
    masses.iter_mut().zip(&in_element).filter(|(_, inside)| !**inside).for_each(|(m, _)| *m = 0.0);
    masses
}

/// A `[solver]` setting that time stepping cannot start with.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum DynamicSettingsError {
    /// ρ is not a finite number > 0.
    #[error("density must be a finite number > 0, found {0}")]
    Density(f64),
    /// A time-stepping setting is out of range.
    #[error(transparent)]
    Params(#[from] ParamError),
}

impl SolverSettings {
    /// [`SolverSettings::dynamics_params`] in a working frame `scale` times the input's,
    /// checked, with the density the masses take ([`lumped_masses`]): what a scene's
    /// simulation and the Python package's `Simulation` start from.
    ///
    /// # Errors
    /// [`DynamicSettingsError`] naming the first bad setting.
    pub fn checked_dynamics_params(&self, scale: f64) -> Result<DynamicsParams, DynamicSettingsError> {
        if !(self.density.is_finite() && self.density > 0.0) {
            return Err(DynamicSettingsError::Density(self.density));
        }
        let params = self.dynamics_params(scale);
        params.validate()?;
        // Iterations per step and the tolerance are the solver's, checked for a time step too.
        DynamicsParams::validate_solver(&self.solver_params())?;
        Ok(params)
    }
}

/// A position group whose targets turn at a constant rate in dynamic mode.
#[derive(Debug, Clone)]
pub struct SpinningHandle {
    /// The group in the system.
    pub id: GroupId,
    /// Its static targets (input frame).
    targets: Vec<DVec3>,
    axis: DVec3,
    center: DVec3,
    deg_per_s: f64,
    frame: WorkingFrame,
}

impl SpinningHandle {
    /// The targets at time `t` (seconds), in the working frame: the static ones turned by
    /// `deg_per_s` · t about the axis through the centre.
    pub fn targets_at(&self, t: f64) -> Vec<DVec3> {
        let turn = glam::DQuat::from_axis_angle(self.axis, (self.deg_per_s * t).to_radians());
        self.targets.iter().map(|&p| self.frame.to_working(self.center + turn * (p - self.center))).collect()
    }
}

impl LoadedScene {
    /// Rest positions in the working frame.
    pub fn rest_positions(&self) -> &[DVec3] {
        &self.rest.positions
    }

    /// Where solves start, working frame: `[mesh] start` when the scene has one, else the rest
    /// shape.
    pub fn start_positions(&self) -> Vec<DVec3> {
        match &self.start {
            Some(start) => self.to_working(start),
            None => self.rest.positions.clone(),
        }
    }

    /// Static solve from [`LoadedScene::start_positions`] (the rest shape unless `[mesh] start`): `iterations` local-global iterations (default: the
    /// scene's steps × iterations). Returns the positions in the working frame.
    ///
    /// # Errors
    /// [`SceneError::Solve`] for a singular system.
    pub fn solve_static(&mut self, iterations: Option<usize>) -> Result<(Vec<DVec3>, SolveReport), SceneError> {
        self.solve_static_with(iterations, |_, _| std::ops::ControlFlow::Continue(()))
    }

    /// [`LoadedScene::solve_static`], calling `after_iteration(k, E_k)` after iteration k (from
    /// 1), as [`System::solve_with`] does: for a progress bar, or to stop early.
    ///
    /// # Errors
    /// As [`LoadedScene::solve_static`].
    pub fn solve_static_with(
        &mut self,
        iterations: Option<usize>,
        after_iteration: impl FnMut(usize, f64) -> std::ops::ControlFlow<()>,
    ) -> Result<(Vec<DVec3>, SolveReport), SceneError> {
        if self.scene.loads.wind.is_some() {
            return Err(SceneError::Invalid {
                path: self.scene.file.clone(),
                entry: "[loads]".into(),
                message:
                    "wind acts in a simulation (its force depends on the faces' velocities): run `shapeup simulate`, \
                          or give a static load as a pressure or a force"
                        .into(),
            });
        }
        let iterations = self.static_iterations(iterations);
        self.warn_of_collider_motion();
        self.warn_of_handle_spin();
        let mut q = self.start_positions();
        if let Some(contact) = self.contact.as_mut().filter(|c| c.is_active()) {
            let report = match solve_static_with_contact(&mut self.system, contact, &mut q, iterations, after_iteration)
            {
                Ok(report) => report,
                Err(source) => return Err(self.solve_error(source)),
            };
            // The report's contacts are those of the result itself.
            contact.record_touching_at(&q, 0.0);
            let inside = contact.stats().inside;
            let colliders = contact.colliders();
            let mut found = Warnings::new();
            found.add_many(
                "inside_collider",
                "vertices of the result are inside a collider (squeezed between two colliders, held there by a hard pin, or left in by too few iterations)",
                inside,
                || {
                    q.iter()
                        .position(|&p| colliders.iter().any(|c| c.closest_at(p, 0.0).distance < 0.0))
                        .map(|v| format!("vertex {v}"))
                        .unwrap_or_default()
                },
            );
            self.warnings.extend(found.for_file(&self.scene.file));
            return Ok((q, report));
        }
        let tolerance = self.scene.solver.tolerance;
        let mut report = match self.system.solve_with(&mut q, iterations, tolerance, after_iteration) {
            Ok(report) => report,
            Err(source) => return Err(self.solve_error(source)),
        };
        if self.start.is_some() {
            self.keep_a_converged_start(&mut q, &mut report, tolerance);
            self.residual_from_rest(&q, &mut report);
        }
        self.warnings.extend(report.warnings().for_file(&self.scene.file));
        Ok((q, report))
    }

    /// A static solve's error for this scene: a non-finite energy where the `[mesh] start`
    /// shape itself has none (coordinates of 1e300, say) names that key and file; any other
    /// is [`SceneError::Solve`].
    fn solve_error(&mut self, source: SolveError) -> SceneError {
        if matches!(source, SolveError::NonFiniteEnergy) && self.start.is_some() {
            let start = self.start_positions();
            if self.system.finite_energy(&start).is_err() {
                let file = self.scene.start_path().unwrap_or_default();
                return SceneError::Invalid {
                    path: self.scene.file.clone(),
                    entry: "[mesh] start".into(),
                    message: format!(
                        "the energy of {} is not finite (its coordinates are too large for the constraints to measure): a start shape is a shape of the mesh at its own scale",
                        file.display()
                    ),
                };
            }
        }
        SceneError::Solve { path: self.scene.file.clone(), source }
    }

    /// A start shape that already meets the tolerance (its first iteration changed E by at
    /// most `tolerance` relative, as the editor's last one did where it saved the shape) is the
    /// result, bit for bit, with no iteration counted: the one step would move it by what the
    /// tolerance leaves (measured up to 7e-6 of the diagonal on stiff models), and the replay
    /// of an editor session must be the shape that was on screen (issue 29).
    fn keep_a_converged_start(&self, q: &mut Vec<DVec3>, report: &mut SolveReport, tolerance: f64) {
        let [first] = report.energies[..] else { return };
        // The start itself must be converged: its first iteration changed E by at most the
        // tolerance, or E was at its round-off floor before it. An iteration that takes E
        // from 42 to round-off meets the solve's stopping test (the floor) but moved the shape
        // (the trial's moved handle: kept 0.5 away from its target).
        let start = report.initial_energy;
        let unchanged = (start - first).abs() <= tolerance * start.abs();
        let at_floor = (0.0..=report.energy_floor).contains(&start);
        if tolerance > 0.0 && (unchanged || at_floor) {
            *q = self.start_positions();
            report.energies.clear();
            report.residual = None;
            report.unconverged = false;
        }
    }

    /// A solve from a start shape near a minimum (the editor saves the shape it converged
    /// to) begins with a gradient near round-off: measured against it, what is left at the end
    /// reads as "short of the minimum" though E did not move. The gradient at the rest shape,
    /// a solve from rest's reference, is taken instead when larger.
    fn residual_from_rest(&mut self, q: &[DVec3], report: &mut SolveReport) {
        let Some(residual) = report.residual.filter(|&r| r > 0.0) else { return };
        // At q last: the system's projections stay those at the result, as the solve left them.
        let rest = self.system.half_gradient_norm_at(&self.rest.positions);
        let end = self.system.half_gradient_norm_at(q);
        if rest > 0.0 && end / rest < residual {
            report.residual = Some(end / rest);
            report.unconverged = end / rest > crate::solver::STATIC_RESIDUAL_LIMIT;
        }
    }

    /// Warns, once, of the colliders whose `velocity` or `spin` a static solve ignores (it
    /// detects contact with the colliders where they are at time 0): a scene that sets them
    /// must not look as if they had moved.
    fn warn_of_collider_motion(&mut self) {
        let moving: Vec<usize> = self
            .scene
            .colliders
            .iter()
            .enumerate()
            .filter(|(_, c)| c.velocity != [0.0; 3] || c.spin.is_some_and(|s| s.deg_per_s != 0.0))
            .map(|(i, _)| i)
            .collect();
        self.warn_once_of_ignored(
            "collider_motion_ignored",
            "collider(s) whose motion (velocity, spin) is ignored in static mode: a static solve keeps each collider where it is at time 0 (`shapeup simulate` moves them)",
            moving.len(),
            moving.first().map(|i| format!("colliders[{i}]")),
        );
    }

    /// Warns, once, of the groups whose `spin` a static solve ignores (it holds a handle at its
    /// targets at time 0), as [`LoadedScene::warn_of_collider_motion`] does for colliders.
    fn warn_of_handle_spin(&mut self) {
        let spinning: Vec<usize> = self
            .scene
            .groups
            .iter()
            .enumerate()
            .filter(|(_, g)| g.targets.spin.is_some_and(|s| s.deg_per_s != 0.0))
            .map(|(i, _)| i)
            .collect();
        self.warn_once_of_ignored(
            "handle_spin_ignored",
            "group(s) whose spin is ignored in static mode: a static solve holds each handle at its targets at time 0 (`shapeup simulate` turns them)",
            spinning.len(),
            spinning.first().map(|&i| format!("constraints[{i}] (\"{}\")", self.scene.groups[i].name)),
        );
    }

    /// One warning of `kind` for the scene file, unless one was already given: the entries
    /// ignored (`count`, the first named), when there are any.
    fn warn_once_of_ignored(&mut self, kind: &str, message: &str, count: usize, first: Option<String>) {
        if count == 0 || self.warnings.count(kind) > 0 {
            return;
        }
        let mut found = Warnings::new();
        found.add_many(kind, message, count, || first.unwrap_or_default());
        self.warnings.extend(found.for_file(&self.scene.file));
    }

    /// The iterations of a static solve: `iterations`, or the scene's steps × iterations.
    pub fn static_iterations(&self, iterations: Option<usize>) -> usize {
        // steps × iterations beyond usize is far more than anyone can wait for: saturate.
        iterations.unwrap_or(self.scene.solver.iterations.saturating_mul(self.scene.solver.steps))
    }

    /// Working-frame positions mapped back to the input frame.
    pub fn to_input(&self, q: &[DVec3]) -> Vec<DVec3> {
        q.iter().map(|&p| self.frame.to_input(p)).collect()
    }

    /// Input-frame positions mapped to the working frame.
    pub fn to_working(&self, positions: &[DVec3]) -> Vec<DVec3> {
        positions.iter().map(|&p| self.frame.to_working(p)).collect()
    }

    /// The input mesh (faces, tetrahedra) with its positions replaced by `q`
    /// (working frame) mapped back; vertices that no constraint touches keep their input
    /// positions bit for bit. [`LoadedScene::output_mesh`] for a volume format.
    pub fn mesh_at(&self, q: &[DVec3]) -> Mesh {
        self.output_mesh(q, true, |v| self.system.is_solved(v))
    }

    /// What an output of the scene at working positions `q` holds, in the input frame: the
    /// whole mesh when `volume` (a format that stores tetrahedra: `.msh`, `.vtu`) or when the
    /// mesh was read with tetrahedra (a surface format then writes their boundary and says
    /// so); for a surface the scene tetrahedralized, that surface: every input vertex in file
    /// order, its faces, without TetGen's points (which come after the input's
    /// vertices), so outputs line up with the input file. Vertices `is_solved` says no
    /// constraint touches, and vertices still exactly where they started (a start kept as it
    /// is), keep their start positions (`[mesh] start`, else the input's) bit for bit (the
    /// round trip through the working frame may change the last bit).
    pub fn output_mesh(&self, q: &[DVec3], volume: bool, is_solved: impl Fn(usize) -> bool) -> Mesh {
        let surface_only = !volume && self.input_vertices < self.mesh.num_vertices();
        let n = if surface_only { self.input_vertices.min(q.len()) } else { q.len() };
        // Vertices the solver does not move keep their start coordinates exactly (no round
        // trip through the working frame).
        let start =
            self.start.as_deref().filter(|s| s.len() == self.mesh.num_vertices()).unwrap_or(&self.mesh.positions);
        let positions = q[..n]
            .iter()
            .zip(start)
            .enumerate()
            .map(
                |(v, (&p, &input))| {
                    if is_solved(v) && p != self.frame.to_working(input) { self.frame.to_input(p) } else { input }
                },
            )
            .collect();
        let mut mesh = self.mesh.with_positions(positions);
        if surface_only {
            mesh.tetrahedra.clear();
        }
        mesh
    }

    /// Lumped masses m_i (working frame): ρ Σ|V_T|/4 on a tetrahedral mesh, else ρ Σ A_t/3
    /// (floored at 1e-9); 0 for a vertex in no element, which is not simulated and keeps its
    /// position (as in static mode).
    /// With a material, its masses in kg ([`material_masses`]).
    pub fn masses(&self) -> Vec<f64> {
        match self.scene.material() {
            Ok(Some(material)) => material_masses(&self.rest, &material),
            _ => lumped_masses(&self.rest, self.scene.solver.density),
        }
    }

    /// How gravity converts to the working frame: with a material it is in m/s² and the frame
    /// is in metres (1); otherwise it is in input units per s² (the frame's scale).
    fn gravity_scale(&self) -> f64 {
        if matches!(self.scene.material(), Ok(Some(_))) { 1.0 } else { self.frame.scale }
    }

    /// The scene's time-stepping settings in the working frame (gravity, an acceleration in
    /// input units per s², scales with lengths; in m/s² with a material; time is not scaled).
    pub fn dynamics_params(&self) -> DynamicsParams {
        self.scene.solver.dynamics_params(self.gravity_scale())
    }

    /// Starts a Projective Dynamics simulation at rest from [`LoadedScene::start_positions`]. The constraint
    /// system moves into the simulation (this scene keeps the mesh and frame, for output).
    ///
    /// # Errors
    /// [`SceneError::Invalid`] for bad dynamic settings (naming the key) or a bad density.
    pub fn start_simulation(&mut self) -> Result<Simulation, SceneError> {
        let invalid =
            |message: String| SceneError::Invalid { path: self.scene.file.clone(), entry: "[solver]".into(), message };
        // Checked before the system moves, so that a refused start leaves this scene whole.
        let params =
            self.scene.solver.checked_dynamics_params(self.gravity_scale()).map_err(|e| invalid(e.to_string()))?;
        let mut system =
            std::mem::replace(&mut self.system, System::new(self.mesh.num_vertices(), SolverParams::default()));
        // Physical groups as time stepping takes them: gravity comes from the inertial target,
        // not a load, and every term is divided by the stiffness k (the inertia is m / (k h²)),
        // so a material's energy and a pressure are multiplied by 1/k to stay their own (a
        // force is a load, which the simulation scales by 1/k itself: `set_load_scale`).
        let physical: Vec<(GroupId, bool, f64)> = system
            .groups()
            .filter(|(_, g)| {
                g.kind == crate::materials::MATERIAL_GROUP
                    || g.kind == crate::materials::PRESSURE_GROUP
                    || g.name == SELF_WEIGHT_GROUP
            })
            .map(|(id, g)| (id, g.name == SELF_WEIGHT_GROUP, g.multiplier))
            .collect();
        for (id, self_weight, multiplier) in physical {
            if self_weight {
                system.remove_group(id);
            } else {
                system.set_multiplier(id, multiplier / params.stiffness).map_err(|e| invalid(e.to_string()))?;
            }
        }
        let mut simulation = Simulation::new(system, self.masses(), self.start_positions(), params)
            .map_err(|e| invalid(e.to_string()))?;
        simulation.set_contact(self.contact.clone()).map_err(|e| invalid(e.to_string()))?;
        if let Some(wind) = &self.scene.loads.wind {
            let wind = wind.wind().map_err(invalid)?;
            simulation.set_wind(Some((wind, self.rest.triangles.clone()))).map_err(|e| invalid(e.to_string()))?;
        }
        Ok(simulation)
    }

    /// Every group with targets that spins (see [`super::Spin`]) in `system` (the scene's,
    /// or the simulation's it moved into), with its static targets resolved once, so that a time step only turns them ([`SpinningHandle::targets_at`]).
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming the group (a selection or targets that do not resolve, or
    /// a zero spin axis).
    pub fn spinning_handles(&self, system: &System) -> Result<Vec<SpinningHandle>, SceneError> {
        let mut out = Vec::new();
        for (i, (spec, &id)) in self.scene.groups.iter().zip(&self.group_ids).enumerate() {
            let Some(spin) = spec.targets.spin else { continue };
            let invalid = |e: super::SpecError| SceneError::Invalid {
                path: self.scene.file.clone(),
                entry: format!("constraints[{i}] (\"{}\")", spec.name),
                message: e.to_string(),
            };
            let (picked, targets) = spec.input_targets(&self.mesh).map_err(invalid)?;
            let (axis, center) = spin.pivot(&targets).map_err(|e| invalid(e.into()))?;
            // In the order the group holds its vertices (what `set_targets` takes).
            let at: std::collections::HashMap<u32, DVec3> =
                picked.iter().zip(&targets).map(|(&v, &t)| (v as u32, t)).collect();
            let held = system.group(id).map(held_vertices).unwrap_or_default();
            let targets = held.iter().map(|v| at.get(v).copied().unwrap_or(DVec3::ZERO)).collect();
            out.push(SpinningHandle { id, targets, axis, center, deg_per_s: spin.deg_per_s, frame: self.frame });
        }
        Ok(out)
    }

    /// E of input-frame positions under the scene's constraints (working frame).
    ///
    /// # Errors
    /// Wrong vertex count, or no constraints.
    pub fn energy_of(&mut self, positions: &[DVec3]) -> Result<crate::solver::Energy, SolveError> {
        let q = self.to_working(positions);
        self.system.energy(&q)
    }
}
