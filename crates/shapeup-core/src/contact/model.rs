//! Contact inside the local-global iterations, with a constant global matrix.
//!
//! Every vertex that takes part has a contact term W_v ‖q_v − p_v(q)‖² whose weight W_v is in
//! the matrix from the start (as the floor's rows are), so the matrix is factored once per run
//! whatever touches what. When nothing touches v its target is p_v = q_v (the iterate of the
//! last global step): the term then only damps the iteration (a proximal term) and vanishes at
//! the fixed point. W_v = [`CONTACT_WEIGHT`] × the vertex's inertia μ_v = m_v/(k h²) in dynamic
//! mode, × its diagonal entry in static mode.
//!
//! Each step:
//! 1. **Detection** ([`ContactModel::begin_step`]) from the step's start x_n and its inertial
//!    prediction s: a vertex near a collider (within the thickness plus twice its predicted
//!    motion), or whose path x_n → x_n + 2(s − x_n) enters one (continuous check), gets a
//!    contact; with self-collision, so do vertex–triangle and edge–edge pairs of the surface
//!    whose swept boxes meet (a BVH over the triangles and one over the edges); and so do the
//!    triangles and edges of the surface near a collider's corners, edges, ridges or a
//!    sphere's or capsule's core, which could cut between the vertices ([`super::features`]).
//!    A contact is a linear gap g(q) = n · Σ_j α_j q_j − c with its normal n, points and
//!    thickness fixed over the step (the side each pair was on at x_n is kept: no
//!    pass-through between detections).
//! 2. **Local step** ([`ContactModel::targets`]): for a collider contact with g < 0, p_v is
//!    q_v moved out by −g along n, then by Coulomb friction (Macklin, Müller, Chentanez and
//!    Kim, "Unified Particle Physics for Real-Time Applications", SIGGRAPH 2014, §6.1): the
//!    tangential slip u_t since x_n, relative to the collider's own motion, is undone when
//!    ‖u_t‖ ≤ μ(−g) (static friction: the vertex sticks) and shortened by μ(−g) otherwise
//!    (kinetic). A self contact's correction is shared by its vertices in proportion to
//!    α_j / W_j, and a vertex in several takes their mean (Jacobi).
//! 3. **Projection** ([`ContactModel::finish_step`]): self contacts still overlapping get a few
//!    Gauss–Seidel position corrections; then what is left inside a collider (the contact term
//!    is a penalty at a finite weight, and a step runs a finite number of iterations) is moved
//!    out along the normal, which also removes the velocity into it, and a path that crossed a
//!    collider is stopped where it entered. When a collider moved something and there are self
//!    contacts, both once more: a collider's push can carry one layer into the next. Colliders
//!    come last, so their thickness holds. The feature contacts are projected before the
//!    vertices', taken again where the surface ended (and found again when it strayed from
//!    its prediction).

use super::collider::Collider;
use super::crossing::{ElementPair, stop_crossings};
use super::features::{
    FeatureContact, Features, PREDICTION_SLACK, detect_feature_contacts, detect_round_contacts_at_end, longest_edge,
};
use super::gap::{Contact, Pair};
use super::self_collision::{EdgeTriangle, Surface, Trees, detect_self_contacts, edges_through_triangles};
use glam::DVec3;
use rayon::prelude::*;

/// Contact settings (working frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// Distance kept between a vertex and a collider or another part of the surface
    /// (working units, ≥ 0).
    pub thickness: f64,
    /// Coulomb μ for self contact.
    pub friction: f64,
    /// Whether the surface collides with itself.
    pub self_collision: bool,
}

/// Colliders, self-collision and the contacts of the current step.
#[derive(Debug, Clone)]
pub struct ContactModel {
    colliders: Vec<Collider>,
    /// Per collider, its points and segments that can cut into the surface.
    features: Vec<Features>,
    params: ContactParams,
    /// The surface's triangles and edges with their BVHs: for self-collision, and for the
    /// colliders' features.
    surface: Option<Surface>,
    /// Vertices that take part (simulated, with mass or in the system).
    active: Vec<bool>,
    /// Collider contacts of the current step (one vertex each).
    contacts: Vec<Contact>,
    /// Self contacts of the current step, then the contacts of the colliders' features with
    /// triangles and edges (`super::features`), the same linear gaps on the surface's side.
    pairs: Vec<Pair>,
    /// How many of `pairs` are self contacts.
    self_pairs: usize,
    /// The element pairs of the step's self contacts, each with its distance at the start
    /// (before [`Pair`]s of the same features are merged): for the crossing check.
    elements: Vec<ElementPair>,
    /// Vertices whose motion the crossing check of the last step changed.
    stopped: usize,
    /// Vertices inside a collider after the last step ([`ContactStats::inside`]).
    inside: usize,
    /// The feature contacts (their gaps are `pairs[self_pairs..]`), with their collider's μ
    /// and motion.
    feature_contacts: Vec<FeatureContact>,
    /// The feature contacts the end of the step projects.
    end_features: Vec<FeatureContact>,
    /// With features: the step's prediction, the surface's longest edge over it, and which
    /// of the surface's trees the step's detection refitted.
    predicted: Vec<DVec3>,
    longest: f64,
    refitted: Trees,
    forces: Vec<DVec3>,
    start: Vec<DVec3>,
    /// Step interval [t0, t1] the contacts were detected for.
    times: (f64, f64),
    /// Per vertex: whether a contact touched it at the end of the last step.
    touching: Vec<bool>,
    touching_count: usize,
    self_count: usize,
    /// Per vertex, its collider contacts (indices into `contacts`).
    by_vertex: Vec<Vec<u32>>,
    /// Per vertex v, its self contacts and its share of each one's correction,
    /// `pair_shares[pair_ptr[v]..pair_ptr[v + 1]]` as (pair, its copies, copies × α_v W_v⁻¹ /
    /// Σ_k α_k² W_k⁻¹), a pair counting as many times as it has copies in the mean:
    /// constant over a step, built at its first local step (empty until then), so that each
    /// iteration gathers per vertex, in parallel, instead of scattering per pair.
    pair_ptr: Vec<u32>,
    pair_shares: Vec<(u32, u32, f64)>,
    /// Per self contact, Σ_j α_j x_j at the step's start (built with `pair_ptr`).
    pair_start: Vec<DVec3>,
    /// Per self contact, its correction at the current iterate, zero when it does not push
    /// (scratch).
    pair_push: Vec<DVec3>,
}

/// What the last step's contact did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ContactStats {
    /// Contacts detected (candidates) this step.
    pub candidates: usize,
    /// Contacts touching at the end of the step (force on, or closer than the thickness).
    pub touching: usize,
    /// Of those, self contacts.
    pub self_touching: usize,
    /// Vertices in a touching contact.
    pub vertices: usize,
    /// Vertices whose motion the crossing check changed (moved in a rigid impact zone or put
    /// back where the step started) because their paths made the surface pass through itself
    /// ([`crate::contact`]'s crossing check; 0 without self-collision).
    pub stopped: usize,
    /// Vertices that ended the step inside a collider: squeezed between two colliders (the
    /// projection out of one pushed them into the other), held back by the crossing check
    /// where a moving collider came over them, or held there by a hard group's pin (contact
    /// does not move a pinned vertex).
    pub inside: usize,
}

/// Most passes of the end-of-step projection of the feature contacts.
const FEATURE_PASSES: usize = 4;

impl ContactModel {
    /// Contact of `n` vertices (those with `active[v]`) with `colliders`, and with themselves
    /// over `triangles` when `params.self_collision`.
    pub fn new(colliders: Vec<Collider>, params: ContactParams, triangles: &[[u32; 3]], active: Vec<bool>) -> Self {
        let n = active.len();
        let features: Vec<Features> = colliders.iter().map(|c| Features::of(&c.shape)).collect();
        let any_features = features.iter().any(|f| f.has_points() || f.has_segments());
        let surface = (params.self_collision || any_features).then(|| Surface::new(triangles, &active));
        ContactModel {
            colliders,
            features,
            params,
            surface,
            active,
            contacts: Vec::new(),
            pairs: Vec::new(),
            self_pairs: 0,
            elements: Vec::new(),
            stopped: 0,
            inside: 0,
            feature_contacts: Vec::new(),
            end_features: Vec::new(),
            predicted: Vec::new(),
            longest: 0.0,
            refitted: Trees { triangles: false, edges: false, vertices: false },
            forces: vec![DVec3::ZERO; n],
            start: Vec::new(),
            times: (0.0, 0.0),
            touching: vec![false; n],
            touching_count: 0,
            self_count: 0,
            by_vertex: vec![Vec::new(); n],
            pair_ptr: Vec::new(),
            pair_shares: Vec::new(),
            pair_start: Vec::new(),
            pair_push: Vec::new(),
        }
    }

    /// The colliders.
    pub fn colliders(&self) -> &[Collider] {
        &self.colliders
    }

    /// The settings.
    pub fn params(&self) -> &ContactParams {
        &self.params
    }

    /// Whether anything can touch anything (a collider, or self-collision).
    pub fn is_active(&self) -> bool {
        !self.colliders.is_empty() || self.params.self_collision
    }

    /// Contacts detected for the current step.
    pub fn num_candidates(&self) -> usize {
        self.contacts.len() + self.pairs.len()
    }

    /// Per vertex: whether it touched something at the end of the last step.
    pub fn touching(&self) -> &[bool] {
        &self.touching
    }

    /// Counts of the last step.
    pub fn stats(&self) -> ContactStats {
        ContactStats {
            candidates: self.num_candidates(),
            touching: self.touching_count,
            self_touching: self.self_count,
            vertices: self.touching.iter().filter(|&&t| t).count(),
            stopped: self.stopped,
            inside: self.inside,
        }
    }

    /// Detection for the step from time t0 (positions `start`) to t1 (predicted `predicted`):
    /// see the [module docs](self). Forces start at 0.
    pub fn begin_step(&mut self, start: &[DVec3], predicted: &[DVec3], t0: f64, t1: f64) {
        self.detect(start, predicted, (t0, t1), 0.0);
    }

    /// [`ContactModel::begin_step`], making collider contacts `reach_slack` farther than the
    /// thickness too.
    fn detect(&mut self, start: &[DVec3], predicted: &[DVec3], (t0, t1): (f64, f64), reach_slack: f64) {
        self.start.clear();
        self.start.extend_from_slice(start);
        self.times = (t0, t1);
        let thickness = self.params.thickness;
        let colliders = &self.colliders;
        let active = &self.active;
        let contacts: Vec<Contact> = (0..start.len())
            .into_par_iter()
            .filter(|&v| active[v])
            .flat_map_iter(|v| {
                let (x, s) = (start[v], predicted[v]);
                let reach = 2.0 * (s - x);
                let margin = thickness + reach_slack + reach.length();
                colliders.iter().filter_map(move |c| {
                    let near = c.closest_from(x, t0, t1);
                    let (point, normal) = if near.distance < margin + c.displacement(x, t0, t1).length() {
                        (near.point, near.normal)
                    } else {
                        let (entry, normal) = c.segment_entry_at(x, t0, x + reach, t1)?;
                        (entry, normal)
                    };
                    let offset = normal.dot(point) + thickness;
                    let shift = c.displacement(point, t0, t1);
                    Some(Contact { vertex: v as u32, normal, offset, friction: c.friction, shift })
                })
            })
            .collect();
        for list in &mut self.by_vertex {
            list.clear();
        }
        for (i, c) in contacts.iter().enumerate() {
            self.by_vertex[c.vertex as usize].push(i as u32);
        }
        self.contacts = contacts;
        self.pair_ptr.clear();
        self.pairs.clear();
        self.feature_contacts.clear();
        self.self_pairs = 0;
        self.elements.clear();
        let has_features = self.has_features();
        if let Some(surface) = &mut self.surface {
            let self_collision = self.params.self_collision;
            let mut trees = Trees { triangles: self_collision, edges: self_collision, vertices: self_collision };
            if has_features || self_collision {
                self.predicted.clear();
                self.predicted.extend_from_slice(predicted);
            }
            if has_features {
                self.longest = longest_edge(surface, start).max(longest_edge(surface, predicted));
                for f in &self.features {
                    let (points, segments) = f.can_cut(self.longest, thickness);
                    trees.triangles |= points;
                    trees.edges |= segments;
                }
            }
            surface.refit(start, predicted, thickness, trees);
            self.refitted = trees;
            if self_collision {
                surface.self_contacts_into(start, predicted, thickness, &mut self.pairs, &mut self.elements);
                self.self_pairs = self.pairs.len();
            }
            if trees.triangles || trees.edges {
                self.feature_contacts = detect_feature_contacts(
                    surface,
                    colliders,
                    &self.features,
                    start,
                    predicted,
                    thickness,
                    self.longest,
                    0.0,
                    (t0, t1),
                );
                self.pairs.extend(self.feature_contacts.iter().map(|f| f.pair));
            }
        }
    }

    /// How many self-collision pairs (vertex–triangle and edge–edge, not neighbours) of the
    /// surface at rest `positions` are already closer than the thickness: a thickness near the
    /// edge length or above makes such pairs of a flat sheet, which then push apart.
    pub fn self_pairs_at_rest(&mut self, positions: &[DVec3]) -> usize {
        let thickness = self.params.thickness;
        if !self.params.self_collision {
            return 0;
        }
        self.surface.as_mut().map_or(0, |surface| {
            let mut fresh = surface.clone();
            detect_self_contacts(&mut fresh, positions, positions, thickness).len()
        })
    }

    /// With self-collision, how many pairs of an edge and a triangle (sharing no vertex) of the
    /// surface at rest `positions` pass through or touch each other: a surface caught in
    /// itself from the start stays so (see `self_collision::edges_through_triangles`).
    /// Returns the count and the first such pair found (its edge's and its triangle's vertices).
    pub fn self_intersections_at_rest(&self, positions: &[DVec3]) -> (usize, Option<EdgeTriangle>) {
        match &self.surface {
            Some(surface) if self.params.self_collision => edges_through_triangles(&mut surface.clone(), positions),
            _ => (0, None),
        }
    }

    /// The contact weight W_v of every vertex, given the weight scale of each (its inertia
    /// μ_v in dynamic mode, its diagonal entry in static mode): [`CONTACT_WEIGHT`] × that for
    /// a vertex that takes part, 0 for the others. Constant for a run: the matrix is factored
    /// with it once.
    pub fn weights(&self, scale: &[f64]) -> Vec<f64> {
        scale.iter().zip(&self.active).map(|(&s, &a)| if a { CONTACT_WEIGHT * s } else { 0.0 }).collect()
    }

    /// The local step of contact at q: each vertex's target p_v (q_v when nothing touches it;
    /// else q_v moved out along the contacts' normals, with Coulomb friction, see the
    /// [module docs](self)), returned as W_v p_v, its share of the global step's right-hand
    /// side. `weights` are [`ContactModel::weights`].
    pub fn targets(&mut self, q: &[DVec3], weights: &[f64]) -> &[DVec3] {
        // Self contacts: each pair's correction at q, in parallel; a vertex then moves by the
        // mean of its pairs' corrections (Jacobi), a pair's correction shared by inverse
        // weight (PBD's rule with W as the masses).
        if !self.pairs.is_empty() {
            if self.pair_ptr.is_empty() {
                self.share_pairs(weights);
            }
            let (friction, self_pairs, features) = (self.params.friction, self.self_pairs, &self.feature_contacts);
            // Σ α_j q_j once per pair: its gap and, when it pushes, its slip since the step's
            // start (Σ α_j x_j, kept per pair for the step, plus a collider's own motion at a
            // feature contact) both come from it.
            self.pairs
                .par_iter()
                .zip(&self.pair_start)
                .enumerate()
                .with_min_len(PAIRS_PER_TASK)
                .map(|(i, (c, &at_start))| {
                    let friction = if i < self_pairs { friction } else { features[i - self_pairs].friction };
                    let u = c.combine(q);
                    let gap = c.normal.dot(u) - c.distance;
                    if gap >= 0.0 {
                        return DVec3::ZERO;
                    }
                    let push = -gap * c.normal;
                    if friction > 0.0 {
                        let slip = u - at_start;
                        push - coulomb(slip - c.normal.dot(slip) * c.normal, friction * -gap)
                    } else {
                        push
                    }
                })
                .collect_into_vec(&mut self.pair_push);
        }
        let start = &self.start;
        let contacts = &self.contacts;
        let by_vertex = &self.by_vertex;
        let (ptr, shares, push) = (&self.pair_ptr, &self.pair_shares, &self.pair_push);
        let self_pairs = self.self_pairs as u32;
        // Per vertex, in parallel: its collider contacts one after the other, then the mean of
        // its feature contacts' corrections less what the first already moved it along them
        // (a vertex and a triangle or edge around it pressed into the same collider are one
        // push, not two), then the mean of its self contacts' corrections; times W_v.
        self.forces.par_iter_mut().enumerate().with_min_len(VERTICES_PER_TASK).for_each(|(v, target)| {
            let mut p = q[v];
            let first = p;
            for &i in &by_vertex[v] {
                let c = &contacts[i as usize];
                let gap = c.gap(p);
                if gap >= 0.0 {
                    continue;
                }
                p -= gap * c.normal;
                if c.friction > 0.0 {
                    let slip = p - start[v] - c.shift;
                    let slip = slip - c.normal.dot(slip) * c.normal;
                    p -= coulomb(slip, c.friction * -gap);
                }
            }
            if let (Some(&from), Some(&to)) = (ptr.get(v), ptr.get(v + 1)) {
                // (self, features)
                let (mut sum, mut count) = ([DVec3::ZERO; 2], [0u32; 2]);
                for &(pair, copies, share) in &shares[from as usize..to as usize] {
                    let x = push[pair as usize];
                    if x != DVec3::ZERO {
                        let kind = usize::from(pair >= self_pairs);
                        sum[kind] += share * x;
                        count[kind] += copies;
                    }
                }
                if count[1] > 0 {
                    let mut mean = sum[1] / f64::from(count[1]);
                    let moved = p - first;
                    let length = moved.length();
                    if length > 0.0 {
                        let along = moved / length;
                        mean -= mean.dot(along).clamp(0.0, length) * along;
                    }
                    p += mean;
                }
                if count[0] > 0 {
                    p += sum[0] / f64::from(count[0]);
                }
            }
            *target = weights[v] * p;
        });
        &self.forces
    }

    /// [`ContactModel::pair_ptr`](Self) and its shares for this step's pairs: vertex j of a
    /// pair takes α_j W_j⁻¹ / Σ_k α_k² W_k⁻¹ of its correction (none when W_j = 0: it is held).
    fn share_pairs(&mut self, weights: &[f64]) {
        let inverse = |v: usize| if weights[v] > 0.0 { 1.0 / weights[v] } else { 0.0 };
        let n = weights.len();
        let share = |c: &Pair| -> [f64; 4] {
            let w: f64 = c.terms().map(|(v, a)| a * a * inverse(v)).sum();
            let mut share = [0.0; 4];
            if w > 0.0 {
                for (k, (v, a)) in c.terms().enumerate() {
                    share[k] = a * inverse(v) / w;
                }
            }
            share
        };
        let all: Vec<[f64; 4]> = self.pairs.par_iter().map(share).collect();
        let mut count = vec![0u32; n + 1];
        for (c, s) in self.pairs.iter().zip(&all) {
            for (&v, &x) in c.vertices.iter().zip(s) {
                if x != 0.0 {
                    count[v as usize + 1] += 1;
                }
            }
        }
        for v in 0..n {
            count[v + 1] += count[v];
        }
        let mut next = count.clone();
        self.pair_shares.clear();
        self.pair_shares.resize(count[n] as usize, (0, 0, 0.0));
        for (i, (c, s)) in self.pairs.iter().zip(&all).enumerate() {
            for (&v, &x) in c.vertices.iter().zip(s) {
                if x != 0.0 {
                    let at = &mut next[v as usize];
                    self.pair_shares[*at as usize] = (i as u32, c.copies, f64::from(c.copies) * x);
                    *at += 1;
                }
            }
        }
        self.pair_ptr = count;
        let start = &self.start;
        self.pairs.par_iter().map(|c| c.combine(start)).collect_into_vec(&mut self.pair_start);
        for (at_start, f) in self.pair_start[self.self_pairs..].iter_mut().zip(&self.feature_contacts) {
            *at_start += f.shift;
        }
    }

    /// Moves the vertices of `positions` that are inside a collider (as it is at time `t`) or
    /// closer than the thickness out to the thickness, along the collider's normal: for a
    /// state that starts overlapping (a rest shape placed in a collider), before its first
    /// step, so that the correction does not become velocity. Returns how many moved.
    pub fn push_out(&self, positions: &mut [DVec3], t: f64) -> usize {
        let thickness = self.params.thickness;
        let colliders = &self.colliders;
        let active = &self.active;
        positions
            .par_iter_mut()
            .enumerate()
            .filter(|(v, _)| active[*v])
            .map(|(_, p)| {
                let mut moved = false;
                for c in colliders {
                    let near = c.closest_at(*p, t);
                    if near.distance < thickness {
                        *p = near.point + thickness * near.normal;
                        moved = true;
                    }
                }
                usize::from(moved)
            })
            .sum()
    }

    /// The end of the step: corrects self contacts still too close, moves `q` out of colliders
    /// and stops paths that crossed one; when a collider moved anything, both once more (a
    /// collider's push can carry one layer into the next: the second pass of self corrections
    /// takes it back out, the last projection keeps the colliders' thickness); records what
    /// touches (see the [module docs](self)). `inverse_mass` weighs how a self contact's
    /// correction is shared (per vertex, 0 for a vertex that must not move).
    pub fn finish_step(&mut self, q: &mut [DVec3], inverse_mass: &[f64]) {
        if !self.pairs.is_empty() {
            self.separate_self_contacts(q, inverse_mass);
        }
        // The colliders' features against the surface as it ended up (found again over the
        // path it took when it strayed from the prediction: a fold can roll over a box's edge
        // within the step), then the vertices.
        let mut pushed = false;
        if self.has_features() {
            self.find_end_feature_contacts(q);
            // Gauss–Seidel passes: two edges on either side of a vertex over a thin bar each
            // push it sideways, together up.
            for _ in 0..FEATURE_PASSES {
                if !self.project_features(q, inverse_mass) {
                    break;
                }
                pushed = true;
            }
        }
        let mut pressed = Vec::new();
        let (moved, mut squeezed) = self.project_out_of_colliders(q, inverse_mass, &mut pressed);
        pushed |= moved > 0;
        if pushed && self.self_pairs > 0 {
            // A layer the colliders pushed to the thickness stays there: the correction goes
            // to the layer above it. Shared by both, it pushed the lower one back in, the
            // projection then put both at the thickness, and two coplanar layers crossed in
            // the plane, where no path check sees it.
            self.separate_self_contacts_on(q, inverse_mass, &pressed);
            squeezed = self.project_out_of_colliders(q, inverse_mass, &mut pressed).1;
        }
        self.stopped = self.stop_crossings(q, inverse_mass);
        self.inside = if self.stopped > 0 { self.count_inside(q) } else { squeezed };
        self.record_touching(q);
    }

    /// Finds the contacts of `q` afresh (a static detection at time `t`) and records what
    /// touches it and how many vertices are inside a collider, as the end of a step does,
    /// without moving anything: for the report of a static solve's result, whose last
    /// detection was some iterations before its end (the surface may have slid off the
    /// contacts found there), or which ran no iteration at all.
    pub fn record_touching_at(&mut self, q: &[DVec3], t: f64) {
        // Vertices resting at the thickness (within round-off of it, outside) touch too: the
        // detection reaches as far as the test of what touches.
        self.detect(q, q, (t, t), touching_tolerance(self.params.thickness));
        self.end_features.clone_from(&self.feature_contacts);
        self.stopped = 0;
        self.inside = self.count_inside(q);
        self.record_touching(q);
    }

    /// What touches at the end of a step (a force on, or within the thickness plus round-off):
    /// [`ContactModel::touching`] and the counts of [`ContactModel::stats`].
    fn record_touching(&mut self, q: &[DVec3]) {
        self.touching.fill(false);
        let tolerance = touching_tolerance(self.params.thickness);
        let touching_pairs: Vec<usize> = self.pairs[..self.self_pairs]
            .par_iter()
            .enumerate()
            .filter(|(_, c)| c.gap(q) <= tolerance)
            .map(|(i, _)| i)
            .collect();
        for &i in &touching_pairs {
            for &v in &self.pairs[i].vertices {
                self.touching[v as usize] = true;
            }
        }
        self.self_count = touching_pairs.len();
        self.touching_count = self.self_count;
        // Feature contacts where the surface ended (the step's α may have slid off).
        for f in &self.end_features {
            if let Some(vertices) = f.touching(q, tolerance) {
                self.touching_count += 1;
                for v in vertices {
                    self.touching[v as usize] = true;
                }
            }
        }
        for c in &self.contacts {
            if c.gap(q[c.vertex as usize]) <= tolerance {
                self.touching_count += 1;
                self.touching[c.vertex as usize] = true;
            }
        }
        self.forces.fill(DVec3::ZERO);
    }

    /// In a time step with self-collision, the fail-safe ([`super::crossing`]): the vertices
    /// of element pairs whose paths from the step's start to `q` cross move in rigid impact
    /// zones (pushed back out of a collider they would enter), or are put back at the start
    /// where a zone holds a vertex with `inverse_mass` 0 (held or driven: it keeps its motion)
    /// or cannot keep out of a collider. Checked: the step's own pairs (every pair whose boxes
    /// in the step's trees meet), and the pairs of the elements with a vertex that ended outside
    /// the element's box in the step's trees ([`Surface::strays`]; up to a translation of the
    /// whole surface, which changes no crossing), found from their own boxes against the
    /// step's trees: the paths of the others stayed in their boxes, so a pair of them is among
    /// the step's own or never met. Returns how many vertices' motion it changed.
    fn stop_crossings(&self, q: &mut [DVec3], inverse_mass: &[f64]) -> usize {
        let Some(surface) = &self.surface else { return 0 };
        if !self.params.self_collision || self.times.1 <= self.times.0 || surface.vertices().is_empty() {
            return 0;
        }
        let (thickness, start, predicted) = (self.params.thickness, &self.start, &self.predicted);
        let vertices = surface.vertices();
        let drift = surface.drift();
        let grow = 0.5 * thickness;
        // Whether an element's path, less `shift`, may have left its box in the step's trees.
        let strays = |element: &[u32], q: &[DVec3], shift: DVec3| {
            surface.strays(element, (start, predicted), |v| q[v as usize] - shift, grow)
        };
        // Grazing within a thousandth of the thickness counts as crossing.
        let tolerance = (1e-3 * thickness).max(1e-12);
        let more = |q: &[DVec3]| -> Vec<ElementPair> {
            // Any translation of the whole path changes no crossing: of the trees' frame and
            // that frame moved by the surface's mean deviation from the prediction, the one
            // fewer vertices stray from.
            let mean = super::ordered_sum(vertices, |v| q[v as usize] - predicted[v as usize]) / vertices.len() as f64;
            let frames = [drift, drift + mean];
            let counts = frames.map(|shift| vertices.par_iter().filter(|&&v| strays(&[v], q, shift)).count());
            let shift = if counts[1] < counts[0] { frames[1] } else { frames[0] };
            if counts[0].min(counts[1]) == 0 {
                return Vec::new();
            }
            let end: Vec<DVec3> = q.par_iter().map(|&p| p - shift).collect();
            surface.pairs_of_strayed(|element| strays(element, q, shift), start, &end, tolerance)
        };
        // Where a zone's vertex would end in a collider's thickness or its path would cross
        // one, the push back out to the thickness (to where it entered, for a path).
        let (colliders, (t0, t1)) = (&self.colliders, self.times);
        let outside = |v: u32, p: DVec3| {
            let from = start[v as usize];
            let mut push: Option<DVec3> = None;
            for c in colliders {
                // As the projection does: a path that crossed goes back to where it entered.
                let out = match c.segment_entry_at(from, t0, p, t1) {
                    Some((entry, normal)) => entry + thickness * normal - p,
                    None => {
                        let near = c.closest_at(p, t1);
                        if near.distance >= thickness - tolerance {
                            continue;
                        }
                        near.point + thickness * near.normal - p
                    }
                };
                if push.is_none_or(|q| out.length_squared() > q.length_squared()) {
                    push = Some(out);
                }
            }
            push
        };
        stop_crossings(&self.elements, more, (vertices, inverse_mass), outside, start, q, tolerance)
    }

    /// How many active vertices of `q` are inside a collider at the step's end.
    fn count_inside(&self, q: &[DVec3]) -> usize {
        let t1 = self.times.1;
        q.par_iter()
            .zip(&self.active)
            .filter(|&(&p, &active)| active && self.colliders.iter().any(|c| c.closest_at(p, t1).distance < 0.0))
            .count()
    }

    /// Whether a collider has features (points or segments) that can cut into the surface.
    fn has_features(&self) -> bool {
        self.features.iter().any(|f| f.has_points() || f.has_segments())
    }

    /// The feature contacts the end of the step projects ([`FeatureContact::project`]): the
    /// step's own when every vertex ended within [`PREDICTION_SLACK`] of the thickness of its
    /// prediction (a pair the detection left out then still keeps 1 − that of it), else those
    /// found again over the path from the step's start to `q`: from the step's trees, the
    /// features' boxes grown by the farthest a vertex ended from its prediction. With only
    /// round colliders in a time step: the step's own and those of the elements that ended
    /// within reach ([`detect_round_contacts_at_end`]).
    fn find_end_feature_contacts(&mut self, q: &[DVec3]) {
        let Some(surface) = &mut self.surface else { return };
        let thickness = self.params.thickness;
        let predicted = &self.predicted;
        let off = surface
            .vertices()
            .par_iter()
            .map(|&v| (q[v as usize] - predicted[v as usize]).length())
            .reduce(|| 0.0, f64::max);
        if off <= PREDICTION_SLACK * thickness {
            self.end_features.clone_from(&self.feature_contacts);
            return;
        }
        let longest = self.longest.max(longest_edge(surface, q));
        let (mut points, mut segments) = (false, false);
        for f in &self.features {
            let (p, s) = f.can_cut(longest, thickness);
            points |= p;
            segments |= s;
        }
        let dynamic = self.times.1 > self.times.0;
        if dynamic && self.features.iter().all(|f| f.is_round() || !(f.has_points() || f.has_segments())) {
            // Only round colliders in a time step: the step's own contacts, and those of the
            // elements that ended within reach (an edge pulled into a thin bar beyond its
            // prediction), made from where they started (the side they came from). A search
            // along the whole path cost cloth-folding a quarter of its step; what passes a bar
            // within one step the step's own contacts catch.
            let found = detect_round_contacts_at_end(
                surface,
                &self.colliders,
                &self.features,
                (&self.start, q),
                thickness,
                longest,
                self.times,
            );
            self.end_features.clone_from(&self.feature_contacts);
            let known: std::collections::HashSet<_> = self.end_features.iter().map(FeatureContact::key).collect();
            self.end_features.extend(found.into_iter().filter(|f| !known.contains(&f.key())));
            return;
        }
        // A tree the step did not refit (the surface stretched past what its features need).
        let stale = Trees {
            triangles: points && !self.refitted.triangles,
            edges: segments && !self.refitted.edges,
            vertices: false,
        };
        if stale.triangles || stale.edges {
            surface.refit(&self.start, predicted, thickness, stale);
        }
        self.end_features = detect_feature_contacts(
            surface,
            &self.colliders,
            &self.features,
            &self.start,
            q,
            thickness,
            longest,
            off,
            self.times,
        );
    }

    /// Projects the end-of-step feature contacts. Whether anything moved. In a time step a
    /// sphere's or a capsule's are projected only where the surface came within half the
    /// thickness, and to there: their linear gap drifts from the round surface as far as the
    /// surface slides around it, and projecting that back to the whole thickness every step
    /// turned into velocity that kept a strain-only cloth on a bar from settling; without any
    /// projection the penalty let a cloth hanging on a thin bar sink through it. A static
    /// solve (t0 = t1) projects all of them to the whole thickness: its positions are the
    /// answer, not a velocity.
    fn project_features(&self, q: &mut [DVec3], inverse_mass: &[f64]) -> bool {
        let dynamic = self.times.1 > self.times.0;
        let give = if dynamic { 0.75 * self.params.thickness } else { 0.0 };
        let mut moved = false;
        for f in &self.end_features {
            moved |= f.project(q, inverse_mass, if f.round { give } else { 0.0 });
        }
        moved
    }

    /// Up to 4 Gauss–Seidel passes of position corrections over the self contacts still too
    /// close, each shared by `inverse_mass`.
    fn separate_self_contacts(&self, q: &mut [DVec3], inverse_mass: &[f64]) {
        self.separate_self_contacts_on(q, inverse_mass, &[]);
    }

    /// [`Self::separate_self_contacts`], where a vertex with a nonzero `pressed` normal (a
    /// collider's, outward: it rests on that collider) is held against a correction that
    /// would push it into the collider. `pressed` is empty or has one entry per vertex.
    fn separate_self_contacts_on(&self, q: &mut [DVec3], inverse_mass: &[f64], pressed: &[DVec3]) {
        let thickness = self.params.thickness;
        // The vertex's share of a correction along `a` n.
        let share = |v: usize, a: f64, normal: DVec3| match pressed.get(v) {
            Some(&n) if n != DVec3::ZERO && a * normal.dot(n) < 0.0 => 0.0,
            _ => inverse_mass[v],
        };
        for _ in 0..4 {
            let mut worst = 0.0f64;
            for c in &self.pairs {
                let gap = c.gap(q);
                if gap >= 0.0 {
                    continue;
                }
                let whole: f64 = c.terms().map(|(v, a)| a * a * inverse_mass[v]).sum();
                let mut w: f64 = c.terms().map(|(v, a)| a * a * share(v, a, c.normal)).sum();
                // What is left free must be able to move the pair: an edge held but for an
                // end at its far side would be thrown 1/α² as far as the gap.
                let held = w < 0.25 * whole;
                if held {
                    w = whole;
                }
                if w <= 0.0 {
                    continue;
                }
                worst = worst.max(-gap);
                let scale = -gap / w;
                for (v, a) in c.terms() {
                    let m = if held { inverse_mass[v] } else { share(v, a, c.normal) };
                    q[v] += scale * a * m * c.normal;
                }
            }
            if worst <= 1e-3 * thickness {
                break;
            }
        }
    }

    /// Moves every active vertex of `q` that may move (`inverse_mass` > 0: a hard group's pin
    /// holds the others where it puts them, inside a collider or not) out of its contacts'
    /// half-spaces and of every collider (as it is at the step's end) to the thickness, with
    /// Coulomb friction on the push, and stops a path that crossed a collider where it entered.
    /// Returns how many moved and how many are left inside one (squeezed between two: still
    /// pushed on the last pass; or held there by a pin); fills
    /// `pressed` with, per vertex, the sum of the outward normals of what it ended within the
    /// thickness of (zero for none).
    fn project_out_of_colliders(
        &self,
        q: &mut [DVec3],
        inverse_mass: &[f64],
        pressed: &mut Vec<DVec3>,
    ) -> (usize, usize) {
        let thickness = self.params.thickness;
        let (t0, t1) = self.times;
        let colliders = &self.colliders;
        let active = &self.active;
        let start = &self.start;
        let by_vertex = &self.by_vertex;
        let contacts = &self.contacts;
        // Within the thickness, plus round-off.
        let near_enough = thickness * (1.0 + 1e-6);
        pressed.clear();
        pressed.resize(q.len(), DVec3::ZERO);
        q.par_iter_mut()
            .zip(pressed.par_iter_mut())
            .enumerate()
            .map(|(v, (p, touched))| {
                if !active[v] {
                    return (false, false);
                }
                if inverse_mass.get(v) == Some(&0.0) {
                    return (false, colliders.iter().any(|c| c.closest_at(*p, t1).distance < 0.0));
                }
                let first = *p;
                for _ in 0..2 {
                    let before = *p;
                    *touched = DVec3::ZERO;
                    // The step's own contacts first: the side each started on.
                    for &i in &by_vertex[v] {
                        let c = &contacts[i as usize];
                        let g = c.gap(*p);
                        if g < 0.0 {
                            *p -= g * c.normal;
                            // The push out is a normal impulse too: Coulomb friction with it.
                            if c.friction > 0.0 {
                                let slip = *p - start[v] - c.shift;
                                *p -= coulomb(slip - c.normal.dot(slip) * c.normal, c.friction * -g);
                            }
                        }
                        if c.gap(*p) <= 1e-6 * thickness {
                            *touched += c.normal;
                        }
                    }
                    for c in colliders {
                        if let Some((entry, normal)) = c.segment_entry_at(start[v], t0, *p, t1) {
                            *p = entry + thickness * normal;
                        }
                        let near = c.closest_at(*p, t1);
                        if near.distance < thickness {
                            let depth = thickness - near.distance;
                            *p = near.point + thickness * near.normal;
                            if c.friction > 0.0 {
                                let slip = *p - start[v] - c.displacement(*p, t0, t1);
                                *p -= coulomb(slip - near.normal.dot(slip) * near.normal, c.friction * depth);
                            }
                        }
                        if near.distance < near_enough {
                            *touched += near.normal;
                        }
                    }
                    if *p == before {
                        return (*p != first, false);
                    }
                }
                // Still pushed on the last pass: squeezed between two colliders. The still ones
                // have the last word: a sphere coming down through a cloth on a floor dragged
                // it 0.19 m under the floor, from where it sprang back at 20 m/s.
                for c in colliders.iter().filter(|c| c.motion.is_static()) {
                    let near = c.closest_at(*p, t1);
                    if near.distance < thickness {
                        *p = near.point + thickness * near.normal;
                    }
                }
                let inside = colliders.iter().any(|c| c.closest_at(*p, t1).distance < 0.0);
                (*p != first, inside)
            })
            .map(|(moved, inside)| (usize::from(moved), usize::from(inside)))
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
    }
}

/// How close to the thickness a contact touches at a step's end (round-off of the projections).
fn touching_tolerance(thickness: f64) -> f64 {
    1e-3 * thickness.max(1e-9)
}

/// Self contacts per parallel task in the per-iteration passes.
const PAIRS_PER_TASK: usize = 4096;

/// Vertices per parallel task in the per-iteration pass.
const VERTICES_PER_TASK: usize = 1024;

/// How many times a vertex's inertia (dynamic mode) or diagonal entry (static mode) its
/// contact weight W_v is: heavy enough that the shape comes to rest against what it touches
/// within a step's iterations, light enough that a free vertex converges as before (the
/// proximal term contracts the error of its slowest modes by W/(μ + W) per iteration at
/// most). The projection at the end of each step removes what penetration is left.
pub const CONTACT_WEIGHT: f64 = 4.0;

/// The Coulomb friction correction of a tangential slip `slip` under a normal correction whose
/// friction bound is `bound` = μ × depth: all of it when ‖slip‖ ≤ bound (static), else `bound`
/// of it along the slip (kinetic).
fn coulomb(slip: DVec3, bound: f64) -> DVec3 {
    let length = slip.length();
    if length <= bound { slip } else { slip * (bound / length) }
}
