//! Assembly: stacks every constraint's rows of C into one sparse matrix and builds the global
//! matrix Σ w_i C_iᵀ C_i, once per change of the constraint set.
//!
//! Vertices that no constraint touches and that have no inertia (static mode, or a massless
//! vertex in dynamic mode) are left out of the system (they keep their positions); the others
//! are renumbered densely ("solved" vertices). Vertices held by a hard group are left out
//! too: their positions are known, so their columns of C move to the right-hand side
//! (min_quad_with_fixed's elimination).

use super::SolveError;
use crate::constraints::{Constraint, RowSink};
use crate::topology::connected_pieces;
use rayon::prelude::*;

/// Rows of one group inside the stacked matrix.
#[derive(Debug, Clone)]
pub(crate) struct GroupRows {
    /// First row of the group.
    pub start: usize,
    /// Row offset of each constraint relative to `start`, plus the end (len = constraints + 1).
    pub offsets: Vec<usize>,
}

impl GroupRows {
    /// The group's rows as a range in the stacked matrix.
    pub fn range(&self) -> std::ops::Range<usize> {
        self.start..self.start + self.offsets.last().copied().unwrap_or(0)
    }
}

/// The stacked selection matrix C, its weighted transpose and the global matrix's pattern.
#[derive(Debug, Clone, Default)]
pub(crate) struct Assembly {
    /// Original index of each solved vertex.
    pub solved: Vec<u32>,
    /// Solved index of each original vertex (`u32::MAX`: not in the system).
    pub solved_index: Vec<u32>,
    /// C as CSR over original vertex indices: row r has entries `c_ptr[r]..c_ptr[r+1]`.
    pub c_ptr: Vec<usize>,
    /// Column (original vertex) of each entry of C.
    pub c_col: Vec<u32>,
    /// Coefficient of each entry of C.
    pub c_val: Vec<f64>,
    /// Element weight ω of each row.
    pub row_weight: Vec<f64>,
    /// Rows of each group.
    pub groups: Vec<GroupRows>,
    /// Group of each row.
    pub row_group: Vec<u32>,
    /// Cᵀ by solved vertex: entries `ct_ptr[v]..ct_ptr[v+1]` are rows (the matrix's pattern).
    pub ct_ptr: Vec<usize>,
    /// Row of each entry of Cᵀ.
    pub ct_row: Vec<u32>,
    /// Lower triangle of the global matrix, CSC over solved vertices: column pointers.
    pub lhs_col_ptr: Vec<u32>,
    /// Row index of each stored entry (sorted within a column, diagonal first).
    pub lhs_row_idx: Vec<u32>,
    /// Per group: Σ_{i in group} ω_i C_iᵀC_i on the pattern (without the multiplier).
    pub group_lhs: Vec<Vec<f64>>,
    /// Per vertex: held by a hard group (empty when none is).
    pub fixed: Vec<bool>,
}

impl Assembly {
    /// Stacks the rows of `groups` (each a list of constraints) over `n` vertices; a vertex
    /// with positive `inertia` is in the system even if no constraint touches it. A vertex
    /// marked in `fixed` (empty: none) is never solved; a group marked in `hard` adds no rows
    /// (it is what fixes them).
    pub fn new(
        n: usize,
        groups: &[&[Box<dyn Constraint>]],
        hard: &[bool],
        fixed: Vec<bool>,
        inertia: Option<&[f64]>,
    ) -> Self {
        let mut a = Assembly { c_ptr: vec![0], fixed, ..Default::default() };
        let mut sink = RowSink::default();
        // Loaded vertices are unknowns even without rows: a load nothing balances is an
        // unanchored piece (an error), not a vertex silently left where it is.
        let mut loaded = Vec::new();
        // The rows' own arrays at their final size at once (growing by doubling held up to
        // twice it; a 556k-vertex mesh has millions of rows).
        let soft = || groups.iter().enumerate().filter(|(g, _)| !hard.get(*g).copied().unwrap_or(false));
        let rows: usize = soft().flat_map(|(_, g)| g.iter()).map(|c| c.num_rows()).sum();
        // A row has at most one entry per vertex of its constraint: an upper bound on C's
        // entries (exact for strain, bending and springs).
        let entries: usize = soft().flat_map(|(_, g)| g.iter()).map(|c| c.num_rows() * c.vertices().len()).sum();
        a.row_weight.reserve_exact(rows);
        a.row_group.reserve_exact(rows);
        a.c_ptr.reserve_exact(rows + 1);
        a.c_col.reserve_exact(entries);
        a.c_val.reserve_exact(entries);
        for (g, constraints) in groups.iter().enumerate() {
            let start = a.row_weight.len();
            let mut offsets = Vec::with_capacity(constraints.len() + 1);
            offsets.push(0);
            if hard.get(g).copied().unwrap_or(false) {
                a.groups.push(GroupRows { start, offsets });
                continue;
            }
            for c in constraints.iter() {
                if let Some(load) = c.load() {
                    loaded.extend_from_slice(load.vertices);
                }
                sink.entries.clear();
                c.rows(&mut sink);
                a.push_rows(&mut sink, c.num_rows(), c.element_weight(), g as u32);
                offsets.push(a.row_weight.len() - start);
            }
            a.groups.push(GroupRows { start, offsets });
        }
        a.number_solved_vertices(n, inertia, &loaded);
        a.build_transpose();
        a.build_lhs_pattern();
        a
    }

    /// Appends one constraint's rows, merging repeated vertices and dropping zero coefficients.
    fn push_rows(&mut self, sink: &mut RowSink, num_rows: usize, weight: f64, group: u32) {
        sink.entries.sort_unstable_by_key(|e| (e.row, e.vertex));
        let mut k = 0;
        for row in 0..num_rows as u32 {
            let row_start = self.c_col.len();
            while k < sink.entries.len() && sink.entries[k].row == row {
                let e = sink.entries[k];
                if self.c_col.len() > row_start && self.c_col.last() == Some(&e.vertex) {
                    if let Some(v) = self.c_val.last_mut() {
                        *v += e.coeff;
                    }
                } else {
                    self.c_col.push(e.vertex);
                    self.c_val.push(e.coeff);
                }
                k += 1;
            }
            // Drop exact zeros (e.g. a cotan weight of a right angle) so that they do not pull
            // an otherwise untouched vertex into the system.
            let mut w = row_start;
            for r in row_start..self.c_col.len() {
                if self.c_val[r] != 0.0 {
                    self.c_col[w] = self.c_col[r];
                    self.c_val[w] = self.c_val[r];
                    w += 1;
                }
            }
            self.c_col.truncate(w);
            self.c_val.truncate(w);
            self.c_ptr.push(self.c_col.len());
            self.row_weight.push(weight);
            self.row_group.push(group);
        }
    }

    fn number_solved_vertices(&mut self, n: usize, inertia: Option<&[f64]>, loaded: &[u32]) {
        let mut touched: Vec<bool> = match inertia {
            Some(mu) => mu.iter().map(|&m| m > 0.0).collect(),
            None => vec![false; n],
        };
        for &v in self.c_col.iter().chain(loaded) {
            touched[v as usize] = true;
        }
        for (t, _) in touched.iter_mut().zip(&self.fixed).filter(|(_, f)| **f) {
            *t = false;
        }
        self.solved_index = vec![u32::MAX; n];
        for (v, _) in touched.iter().enumerate().filter(|(_, t)| **t) {
            self.solved_index[v] = self.solved.len() as u32;
            self.solved.push(v as u32);
        }
    }

    /// Number of solved vertices.
    pub fn num_solved(&self) -> usize {
        self.solved.len()
    }

    /// Number of rows of the stacked C.
    pub fn num_rows(&self) -> usize {
        self.row_weight.len()
    }

    /// Whether vertex `v` is held by a hard group.
    pub fn is_fixed(&self, v: usize) -> bool {
        self.fixed.get(v).copied().unwrap_or(false)
    }

    fn build_transpose(&mut self) {
        let ns = self.num_solved();
        let mut count = vec![0usize; ns + 1];
        // Columns of fixed vertices are not in Cᵀ's solved rows (they go to the right-hand side).
        for &v in &self.c_col {
            if let Some(s) = self.solved(v) {
                count[s + 1] += 1;
            }
        }
        for i in 0..ns {
            count[i + 1] += count[i];
        }
        let mut next = count.clone();
        self.ct_row = vec![0; count[ns]];
        for r in 0..self.num_rows() {
            for k in self.c_ptr[r]..self.c_ptr[r + 1] {
                let Some(s) = self.solved(self.c_col[k]) else { continue };
                self.ct_row[next[s]] = r as u32;
                next[s] += 1;
            }
        }
        self.ct_ptr = count;
    }

    /// The entries (solved row ≥ solved column) of Σ CᵀC's lower triangle, then per group
    /// Σ ω C_iᵀC_i on that pattern. Column b holds every a ≥ b sharing a row of C with b,
    /// found through Cᵀ (one small sort per column instead of one global sort).
    fn build_lhs_pattern(&mut self) {
        let ns = self.num_solved();
        let columns: Vec<Vec<u32>> = (0..ns)
            .into_par_iter()
            .map(|b| {
                // The diagonal always, for inertia on vertices no constraint touches.
                let mut rows: Vec<u32> = vec![b as u32];
                for k in self.ct_ptr[b]..self.ct_ptr[b + 1] {
                    let r = self.ct_row[k] as usize;
                    for &v in &self.c_col[self.c_ptr[r]..self.c_ptr[r + 1]] {
                        if let Some(a) = self.solved(v).filter(|&a| a >= b) {
                            rows.push(a as u32);
                        }
                    }
                }
                rows.sort_unstable();
                rows.dedup();
                rows
            })
            .collect();
        let mut col_ptr = Vec::with_capacity(ns + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::with_capacity(columns.iter().map(Vec::len).sum());
        for column in columns {
            row_idx.extend(column);
            col_ptr.push(row_idx.len() as u32);
        }
        self.lhs_col_ptr = col_ptr;
        self.lhs_row_idx = row_idx;
        self.group_lhs = (0..self.groups.len()).into_par_iter().map(|g| self.group_values(g)).collect();
    }

    /// Σ_{rows r of group g} ω_r c_r c_rᵀ on the lower-triangle pattern.
    fn group_values(&self, g: usize) -> Vec<f64> {
        let mut values = vec![0.0; self.lhs_row_idx.len()];
        for r in self.groups[g].range() {
            let (lo, hi) = (self.c_ptr[r], self.c_ptr[r + 1]);
            for a in lo..hi {
                let Some(sa) = self.solved(self.c_col[a]) else { continue };
                for b in lo..hi {
                    let Some(sb) = self.solved(self.c_col[b]) else { continue };
                    if sa >= sb {
                        let slot = self.slot(sa, sb);
                        values[slot] += self.row_weight[r] * self.c_val[a] * self.c_val[b];
                    }
                }
            }
        }
        values
    }

    /// The solved index of vertex `v`, if it is solved.
    pub(super) fn solved(&self, v: u32) -> Option<usize> {
        let s = self.solved_index[v as usize];
        (s != u32::MAX).then_some(s as usize)
    }

    /// Index of entry (row, col), row ≥ col, in the lower-triangle storage.
    pub fn slot(&self, row: usize, col: usize) -> usize {
        let (lo, hi) = (self.lhs_col_ptr[col] as usize, self.lhs_col_ptr[col + 1] as usize);
        // The pattern holds every pair of every row, so the entry exists.
        lo + self.lhs_row_idx[lo..hi].partition_point(|&r| (r as usize) < row)
    }

    /// Checks that every connected piece of the solved vertices is anchored: some row in it is
    /// not translation invariant (its coefficients do not sum to zero, as a position or floor
    /// row) and has a positive weight (`multipliers`: per group). Otherwise the static system is singular: translating the piece costs nothing.
    pub fn check_anchored(&self, multipliers: &[f64]) -> Result<(), SolveError> {
        let ns = self.num_solved();
        let links: Vec<Vec<u32>> = (0..self.num_rows())
            .map(|r| {
                let row = &self.c_col[self.c_ptr[r]..self.c_ptr[r + 1]];
                row.iter().filter_map(|&v| self.solved(v).map(|s| s as u32)).collect()
            })
            .collect();
        let (piece, count) = connected_pieces(ns, links.iter().map(|l| l.as_slice()));
        let mut anchored = vec![false; count];
        // Pieces that would be anchored but for a weight of 0.
        let mut weightless = vec![false; count];
        for (r, link) in links.iter().enumerate() {
            let vals = &self.c_val[self.c_ptr[r]..self.c_ptr[r + 1]];
            let sum: f64 = vals.iter().sum();
            let scale: f64 = vals.iter().map(|v| v.abs()).sum();
            let weight = self.row_weight[r] * multipliers[self.row_group[r] as usize];
            // A row through a fixed vertex ties its free vertices to a known point.
            let touches_fixed = self.c_col[self.c_ptr[r]..self.c_ptr[r + 1]].iter().any(|&v| self.is_fixed(v as usize));
            if let Some(&v) = link.first()
                && (touches_fixed || sum.abs() > 1e-9 * scale)
            {
                let p = piece[v as usize] as usize;
                if weight > 0.0 {
                    anchored[p] = true;
                } else {
                    weightless[p] = true;
                }
            }
        }
        if let Some(p) = anchored.iter().position(|a| !a) {
            let members: Vec<usize> = (0..ns).filter(|&v| piece[v] as usize == p).collect();
            return Err(SolveError::Unanchored {
                piece_size: members.len(),
                vertex: members.first().map(|&v| self.solved[v] as usize).unwrap_or(0),
                num_pieces: count,
                only_zero_weight: weightless[p],
            });
        }
        Ok(())
    }
}
