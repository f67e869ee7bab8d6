//! The right-hand side's constant part: inertia (dynamic mode), loads and held vertices, and
//! where each entry of C lands in it. Recomputed when they change, never per iteration.

use super::{SolveError, Stale, System, check_weight};
use glam::DVec3;

impl System {
    /// Sets per-vertex inertia weights μ_i ≥ 0 (dynamic mode: μ_i = m_i / (k h²)), adding
    /// diag(μ) to the global matrix and μ s to its right-hand side (see
    /// [`System::set_inertial_target`]); `None` goes back to the static problem. Switching
    /// modes re-assembles (every vertex is solved in dynamic mode); new values only refactor.
    ///
    /// # Errors
    /// [`SolveError::WrongLength`], or [`SolveError::BadWeight`] for a negative or non-finite μ.
    pub fn set_inertia(&mut self, inertia: Option<Vec<f64>>) -> Result<(), SolveError> {
        if let Some(mu) = &inertia {
            self.check_length(mu)?;
            if let Some(&bad) = mu.iter().find(|m| crate::constraints::check_weight(**m).is_err()) {
                return Err(SolveError::BadWeight { name: "inertia".into(), value: bad });
            }
        }
        match (&self.inertia, &inertia) {
            (None, None) => return Ok(()),
            (Some(old), Some(new)) if old == new => return Ok(()),
            // Which vertices have inertia decides which are solved.
            (Some(old), Some(new)) if old.iter().zip(new).all(|(a, b)| (*a > 0.0) == (*b > 0.0)) => {
                self.mark(Stale::Values)
            }
            (Some(_), Some(_)) => self.mark(Stale::Pattern),
            _ => self.mark(Stale::Pattern),
        }
        self.inertia = inertia;
        Ok(())
    }

    /// The inertia weights, if in dynamic mode.
    pub fn inertia(&self) -> Option<&[f64]> {
        self.inertia.as_deref()
    }

    /// Sets the inertial target s (all vertices, working frame) that diag(μ) pulls towards;
    /// ignored in static mode. Changing it needs no refactorization.
    ///
    /// # Errors
    /// [`SolveError::WrongLength`].
    pub fn set_inertial_target(&mut self, target: &[DVec3]) -> Result<(), SolveError> {
        self.check_length(target)?;
        self.inertial_target.clear();
        self.inertial_target.extend_from_slice(target);
        self.update_constant_rhs();
        self.map_changed = true;
        Ok(())
    }

    /// [`System::constant_rhs`](Self): μ s (dynamic mode) plus the held vertices' share, in one
    /// pass over the solved vertices (this runs once per time step).
    pub(super) fn update_constant_rhs(&mut self) {
        self.constant_rhs.clear();
        let a = &self.assembly;
        if self.is_assembled() && !self.load_rhs.is_empty() {
            // Loads are rare and static: the general form, without the fast paths below.
            self.constant_rhs.extend(a.solved.iter().enumerate().map(|(s, &v)| {
                let v = v as usize;
                let inertial = match &self.inertia {
                    Some(mu) => mu[v] * self.inertial_target.get(v).copied().unwrap_or(DVec3::ZERO),
                    None => DVec3::ZERO,
                };
                inertial + self.held_rhs.get(s).copied().unwrap_or(DVec3::ZERO) + self.load_rhs[s]
            }));
            return;
        }
        match (&self.inertia, self.held_rhs.is_empty()) {
            _ if !self.is_assembled() => {}
            (None, true) => {}
            (None, false) => self.constant_rhs.extend_from_slice(&self.held_rhs),
            (Some(mu), held_is_empty) => {
                let target = &self.inertial_target;
                self.constant_rhs.extend(a.solved.iter().enumerate().map(|(s, &v)| {
                    let v = v as usize;
                    let inertial = mu[v] * target.get(v).copied().unwrap_or(DVec3::ZERO);
                    if held_is_empty { inertial } else { inertial + self.held_rhs[s] }
                }));
            }
        }
    }

    /// Sets the factor every load is multiplied by besides its group's multiplier (1 by
    /// default; dynamic mode sets 1/k so that a load is the physical force g f).
    ///
    /// # Errors
    /// [`SolveError::BadWeight`] for a negative or non-finite scale.
    pub fn set_load_scale(&mut self, scale: f64) -> Result<(), SolveError> {
        check_weight("load scale", scale)?;
        if scale != self.load_scale {
            self.load_scale = scale;
            self.update_load_rhs();
            self.update_constant_rhs();
            self.map_changed = true;
        }
        Ok(())
    }

    /// [`System::load_rhs`](Self): Σ g f_v per solved vertex over every group's loads.
    pub(super) fn update_load_rhs(&mut self) {
        self.load_rhs.clear();
        if !self.is_assembled() {
            return;
        }
        let a = &self.assembly;
        let mut any = false;
        for group in self.slots.iter().flatten() {
            for load in group.constraints.iter().filter_map(|c| c.load()) {
                if !any {
                    self.load_rhs.resize(a.num_solved(), DVec3::ZERO);
                    any = true;
                }
                for (&v, f) in load.vertices.iter().zip(load.forces) {
                    if let Some(b) = a.solved_index.get(v as usize).and_then(|&s| self.load_rhs.get_mut(s as usize)) {
                        *b += self.load_scale * group.multiplier * *f;
                    }
                }
            }
        }
    }

    /// The loads' share of E at q: −2 Σ g f_v · (q_v − x⁰_v) over the groups in `slots`.
    pub(super) fn load_energy(&self, q: &[DVec3], slots: impl IntoIterator<Item = usize>) -> f64 {
        let mut e = 0.0;
        for group in slots.into_iter().filter_map(|s| self.slots.get(s).and_then(Option::as_ref)) {
            for load in group.constraints.iter().filter_map(|c| c.load()) {
                e += self.load_scale * group.multiplier * load.energy(q);
            }
        }
        e
    }

    /// [`System::held_rhs`](Self) from the held vertices' points and the current weights, then
    /// the constant right-hand side.
    pub(super) fn update_held_rhs(&mut self) {
        self.held_rhs.clear();
        let a = &self.assembly;
        if self.is_assembled() && !self.held.is_empty() {
            let mut at = vec![DVec3::ZERO; self.num_vertices];
            for &(v, x) in &self.held {
                at[v as usize] = x;
            }
            // Per row, the fixed vertices' part of C_r x; then minus Cᵀ W of it per solved vertex.
            let fixed_part: Vec<DVec3> = (0..a.num_rows())
                .map(|r| {
                    (a.c_ptr[r]..a.c_ptr[r + 1])
                        .filter(|&k| a.is_fixed(a.c_col[k] as usize))
                        .map(|k| a.c_val[k] * at[a.c_col[k] as usize])
                        .sum()
                })
                .collect();
            self.held_rhs.resize(a.num_solved(), DVec3::ZERO);
            for (r, fixed) in fixed_part.iter().enumerate().filter(|(_, f)| **f != DVec3::ZERO) {
                for k in a.c_ptr[r]..a.c_ptr[r + 1] {
                    if let Some(b) = self.held_rhs.get_mut(a.solved_index[a.c_col[k] as usize] as usize) {
                        *b -= self.rhs_map.weighted[k] * *fixed;
                    }
                }
            }
        }
        self.update_constant_rhs();
    }

    /// Moves the held vertices of `q` to their points.
    pub(super) fn pin_held(&self, q: &mut [DVec3]) {
        for &(v, x) in &self.held {
            q[v as usize] = x;
        }
    }

    /// The hard groups' vertices and points, in slot order.
    pub(super) fn collect_held(&self) -> Result<Vec<(u32, DVec3)>, SolveError> {
        let mut held = Vec::new();
        for group in self.slots.iter().flatten().filter(|g| g.hard) {
            for c in &group.constraints {
                let (vertices, points) = c
                    .held_points()
                    .ok_or_else(|| SolveError::NotHardable { name: group.name.clone(), kind: group.kind.clone() })?;
                held.extend(vertices.iter().copied().zip(points.iter().copied()));
            }
        }
        Ok(held)
    }

    /// Applies the current multipliers to W C: g · w_r · c_rk per entry of C.
    pub(super) fn update_weights(&mut self) {
        let g = self.multipliers();
        let a = &self.assembly;
        self.rhs_map.weighted.clear();
        // One allocation of the final size (growing by doubling held up to twice it).
        self.rhs_map.weighted.reserve_exact(a.c_val.len());
        for r in 0..a.num_rows() {
            let w = g[a.row_group[r] as usize] * a.row_weight[r];
            self.rhs_map.weighted.extend(a.c_val[a.c_ptr[r]..a.c_ptr[r + 1]].iter().map(|c| w * c));
        }
    }

    /// Where each entry of C lands in the factor's permuted right-hand side (after a new
    /// symbolic analysis).
    pub(super) fn update_rhs_slots(&mut self) {
        let (a, Some(factor)) = (&self.assembly, &self.factor) else { return };
        let forward = factor.permutation();
        let mut position = vec![u32::MAX; a.num_solved()];
        for (i, &s) in forward.iter().enumerate() {
            position[s as usize] = i as u32;
        }
        self.rhs_map.slot = a
            .c_col
            .iter()
            .map(|&v| position.get(a.solved_index[v as usize] as usize).copied().unwrap_or(u32::MAX))
            .collect();
    }
}
