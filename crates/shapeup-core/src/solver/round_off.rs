//! Groups the factorization cannot resolve: where a group acts, its terms w g c² are below
//! round-off of the matrix diagonal A_vv = Σ (all groups, inertia, contact), so that A is the
//! same to its last digits with or without it. Weights 10¹³ or more apart do this (springs at
//! 1e8 against handles at 1e-8): what the handle holds is left to round-off. When it is the
//! only anchor of a piece, the pivot of that piece's free motion is the handle's weight plus
//! the round-off of the others', of the same size: the factorization may find the matrix
//! singular, or solve and move the piece by a ratio of round-offs (right or wrong, by luck).

use super::System;

/// A group is lost to round-off when, on every solved vertex it touches, its share of the
/// diagonal, w g c² / A_vv, is at most this (about 450 ε: a term this small changes A_vv in its
/// last two or three digits at most).
pub const ROUND_OFF_SHARE: f64 = 1e-13;

/// A group lost to round-off ([`ROUND_OFF_SHARE`]), and the group that dwarfs it where it
/// holds the most.
#[derive(Debug, Clone, PartialEq)]
pub struct LostGroup {
    /// Its name.
    pub name: String,
    /// Its multiplier (the scene's `weight`).
    pub weight: f64,
    /// Its largest share of a diagonal entry.
    pub share: f64,
    /// The group with the largest term on that diagonal entry.
    pub dominant: String,
    /// That group's multiplier.
    pub dominant_weight: f64,
    /// What is lost is the inertia m / (k h²) of a time step (`name` and `weight` then say
    /// "inertia" and its largest value): the stiffness is too high for the time step.
    pub is_inertia: bool,
    /// What dwarfs it is the inertia (`dominant_weight` its value there), not a group: the
    /// time step too short or the stiffness too low for the group.
    pub dominant_is_inertia: bool,
}

impl LostGroup {
    /// `"NAME" (weight W), below round-off of "OTHER" (weight W')`: the warning's and the
    /// error's words.
    pub fn describe(&self) -> String {
        let three = crate::text::three_digits;
        let lost = if self.is_inertia {
            format!("the inertia m / (stiffness · time_step²) (of every vertex, the largest {})", three(self.weight))
        } else {
            format!("\"{}\" (weight {:e})", self.name, self.weight)
        };
        if self.dominant_is_inertia {
            format!("{lost} against the inertia m / (stiffness · time_step²) ({} there)", three(self.dominant_weight))
        } else {
            format!("{lost} against \"{}\" (weight {:e})", self.dominant, self.dominant_weight)
        }
    }
}

/// The `groups_lost_to_round_off` warning for `lost` (none when empty): every door, static
/// solves and time steps, says it in these words.
pub fn add_lost_groups_warning(found: &mut crate::warnings::Warnings, lost: &[LostGroup]) {
    let inertia = if lost.iter().any(|l| l.is_inertia || l.dominant_is_inertia) {
        " (where the inertia of a time step is one of them: change `stiffness` or `time_step`)"
    } else {
        ""
    };
    found.add_many(
        "groups_lost_to_round_off",
        &format!(
            "group(s) whose terms are below round-off of the others where they act (at most {ROUND_OFF_SHARE:e} of the matrix's diagonal): the factorization cannot resolve them, so what they hold is left to round-off (the shape may ignore them, or the system read as singular); bring the weights within 1e12 of each other{inertia}"
        ),
        lost.len(),
        || lost.first().map(LostGroup::describe).unwrap_or_default(),
    );
}

impl System {
    /// The groups of positive weight lost to round-off in the matrix whose values (lower
    /// triangle, as factored) are `values`, with multipliers `g` per group in assembly order.
    pub(super) fn groups_lost_to_round_off(&self, values: &[f64], g: &[f64]) -> Vec<LostGroup> {
        let a = &self.assembly;
        let diagonal: Vec<f64> = (0..a.num_solved()).map(|s| values[a.slot(s, s)]).collect();
        // Per group: its largest share and the solved vertex where it has it.
        let mut best: Vec<Option<(f64, usize)>> = vec![None; g.len()];
        let terms = |r: usize| {
            let weight = a.row_weight[r] * g[a.row_group[r] as usize];
            a.c_col[a.c_ptr[r]..a.c_ptr[r + 1]]
                .iter()
                .zip(&a.c_val[a.c_ptr[r]..a.c_ptr[r + 1]])
                .filter_map(move |(&v, &c)| a.solved(v).map(|s| (s, weight * c * c)))
        };
        for r in 0..a.num_rows() {
            let group = a.row_group[r] as usize;
            for (s, term) in terms(r) {
                let share = if diagonal[s] > 0.0 { term / diagonal[s] } else { 1.0 };
                if best[group].is_none_or(|(b, _)| share > b) {
                    best[group] = Some((share, s));
                }
            }
        }
        // Each group's terms on the diagonal entry of solved vertex s (one pass over the rows:
        // only when something is lost).
        let terms_at = |s: usize| {
            let mut per_group = vec![0.0_f64; g.len()];
            for r in 0..a.num_rows() {
                for (t, term) in terms(r) {
                    if t == s {
                        per_group[a.row_group[r] as usize] += term;
                    }
                }
            }
            per_group
        };
        let name = |group: usize| self.slots[self.order[group]].as_ref().map_or(String::new(), |g| g.name.clone());
        let mut lost = Vec::new();
        for (group, found) in best.iter().enumerate() {
            let Some((share, s)) = *found else { continue };
            if g[group] <= 0.0 || share > ROUND_OFF_SHARE {
                continue;
            }
            // The group with the largest term where this one holds the most.
            let per_group = terms_at(s);
            let dominant = (0..g.len()).max_by(|&i, &j| per_group[i].total_cmp(&per_group[j])).unwrap_or(group);
            // What the groups leave of the diagonal is the inertia (and contact's rows).
            let inertia = self.inertia.as_ref().map_or(0.0, |mu| mu[a.solved[s] as usize]);
            let dominant_is_inertia = inertia > per_group[dominant];
            lost.push(LostGroup {
                name: name(group),
                weight: g[group],
                share,
                dominant: if dominant_is_inertia { String::new() } else { name(dominant) },
                dominant_weight: if dominant_is_inertia { inertia } else { g[dominant] },
                is_inertia: false,
                dominant_is_inertia,
            });
        }
        // A time step whose inertia is below round-off everywhere: gravity and momentum are
        // lost, and the body stays where the constraints hold it.
        if let Some(mu) = &self.inertia {
            let share = |s: usize| if diagonal[s] > 0.0 { mu[a.solved[s] as usize] / diagonal[s] } else { 1.0 };
            let largest = (0..a.num_solved()).max_by(|&i, &j| share(i).total_cmp(&share(j)));
            if let Some(s) = largest.filter(|&s| mu[a.solved[s] as usize] > 0.0 && share(s) <= ROUND_OFF_SHARE) {
                let per_group = terms_at(s);
                let dominant = (0..g.len()).max_by(|&i, &j| per_group[i].total_cmp(&per_group[j])).unwrap_or(0);
                lost.push(LostGroup {
                    name: "inertia".into(),
                    weight: mu.iter().copied().fold(0.0, f64::max),
                    share: share(s),
                    dominant: name(dominant),
                    dominant_weight: g.get(dominant).copied().unwrap_or(0.0),
                    is_inertia: true,
                    dominant_is_inertia: false,
                });
            }
        }
        lost
    }
}
