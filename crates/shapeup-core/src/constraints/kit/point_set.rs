//! Point-set constraints (line, plane, circle, sphere): a primitive fitted to the selected points
//! and the points projected onto it. Everything but the fit is the same for all of them — one
//! mean-centred row per vertex (C = I − 11ᵀ/k, [`centred_rows`]), element weight 1, the
//! projection computed about the centroid and moved to the rows' frame — and lives here, in
//! [`PointSet`]; a type file supplies its [`Primitive`] (the projection of the centred rows and
//! the distance from the set) and its build, from [`one_set`] or [`faces_or_set`].

use std::fmt;
use std::marker::PhantomData;

use glam::DVec3;

use crate::constraints::contract::{BuildContext, Constraint, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::non_empty;
use crate::constraints::kit::faces::{WHOLE_SELECTION, selected_faces};
use crate::constraints::kit::fit::rms_radius;
use crate::constraints::kit::vertex_set::{centred, centred_rows, recentre, to_row_frame, vertex_set};
use crate::constraints::params::Params;

/// The primitive of a point-set constraint: the set of centred configurations of k points that
/// lie on it, and the nearest such configuration to given centred rows.
pub trait Primitive: 'static {
    /// The type's name in scene files.
    const KIND: &'static str;
    /// The fewest vertices a constraint takes.
    const MIN_VERTICES: usize;

    /// Writes into `out` (as long as `d`) the nearest centred configuration on the primitive to
    /// the rows `d` (the selected points about their centroid).
    fn project(d: &[DVec3], out: &mut [DVec3]);

    /// The distance of rows `p` (in the frame of C q) from the set of centred configurations.
    fn set_residual(p: &[DVec3]) -> f64;

    /// The error a report gives for `C q`: by default [`Primitive::set_residual`] (see
    /// [`Constraint::violation`]).
    fn violation(cq: &[DVec3]) -> f64 {
        Self::set_residual(cq)
    }
}

/// A set of vertices kept on one primitive `P` (a line, plane, circle or sphere).
pub struct PointSet<P> {
    vertices: Box<[u32]>,
    primitive: PhantomData<fn() -> P>,
}

impl<P: Primitive> PointSet<P> {
    /// Keeps `vertices` (distinct) on one primitive; `None` with fewer than
    /// [`Primitive::MIN_VERTICES`].
    pub fn new(vertices: Vec<u32>) -> Option<Self> {
        (vertices.len() >= P::MIN_VERTICES).then(|| PointSet { vertices: vertices.into(), primitive: PhantomData })
    }
}

impl<P> Clone for PointSet<P> {
    fn clone(&self) -> Self {
        PointSet { vertices: self.vertices.clone(), primitive: PhantomData }
    }
}

impl<P: Primitive> fmt::Debug for PointSet<P> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("PointSet").field("kind", &P::KIND).field("vertices", &self.vertices).finish()
    }
}

impl<P: Primitive> Constraint for PointSet<P> {
    fn kind(&self) -> &'static str {
        P::KIND
    }
    fn vertices(&self) -> &[u32] {
        &self.vertices
    }
    fn element_weight(&self) -> f64 {
        1.0
    }
    fn num_rows(&self) -> usize {
        self.vertices.len()
    }
    fn rows(&self, sink: &mut RowSink) {
        centred_rows(&self.vertices, sink);
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        P::project(&centred(&self.vertices, q), out);
        to_row_frame(&self.vertices, q, out);
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        P::set_residual(p)
    }
    fn violation(&self, cq: &[DVec3]) -> f64 {
        P::violation(cq)
    }
}

/// The projection of a fitted primitive (circle, sphere) of centred rows `d` into `out`, the fit
/// done at unit scale: `project` gets the points about their centroid at unit RMS radius and
/// writes their projection; it is scaled back and recentred. Coincident points lie on every
/// circle and sphere through them, and non-finite input is taken as given: both are written
/// about their centroid without a fit.
pub(crate) fn project_at_unit_scale(d: &[DVec3], out: &mut [DVec3], project: impl FnOnce(&[DVec3], &mut [DVec3])) {
    let (mean, scale) = rms_radius(d);
    if !(scale > 0.0 && scale.is_finite()) {
        for (o, &x) in out.iter_mut().zip(d) {
            *o = x - mean;
        }
        return;
    }
    let points: Vec<DVec3> = d.iter().map(|&x| (x - mean) / scale).collect();
    project(&points, out);
    for o in out.iter_mut() {
        *o *= scale;
    }
    recentre(out);
}

/// One [`PointSet`] over all the selected vertices: the build of a type without options. `why`
/// says why fewer than [`Primitive::MIN_VERTICES`] points are refused.
///
/// # Errors
/// [`ConstraintError::NothingSelected`] or [`ConstraintError::Invalid`] for too few selected
/// vertices.
pub(crate) fn one_set<P: Primitive>(
    ctx: &BuildContext,
    why: &str,
) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
    let vertices = vertex_set(ctx, P::KIND, P::MIN_VERTICES, why)?;
    let set = PointSet::<P>::new(vertices).ok_or_else(|| ConstraintError::Invalid {
        kind: P::KIND,
        problem: format!("needs at least {} vertices", P::MIN_VERTICES),
    })?;
    Ok(vec![Box::new(set)])
}

/// A [`PointSet`] on every selected polygon face of 4 or more corners, or, with
/// `whole_selection = true`, one over all the selected vertices: the build of a face type.
/// `why_set` says why fewer than [`Primitive::MIN_VERTICES`] points are refused, `why_faces` why
/// triangles are.
///
/// # Errors
/// [`ConstraintError`]: a bad `whole_selection`, too few selected vertices, or no face of 4 or
/// more corners.
pub(crate) fn faces_or_set<P: Primitive>(
    ctx: &BuildContext,
    params: &mut Params,
    why_set: &str,
    why_faces: &str,
) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
    let sets: Vec<Vec<u32>> = if params.flag(P::KIND, &WHOLE_SELECTION)? {
        vec![vertex_set(ctx, P::KIND, P::MIN_VERTICES, why_set)?]
    } else {
        selected_faces(ctx, P::KIND, why_faces)?
    };
    let built = sets.into_iter().filter_map(PointSet::<P>::new).map(|c| Box::new(c) as Box<dyn Constraint>).collect();
    non_empty(built, P::KIND, "faces of 4 or more corners")
}
