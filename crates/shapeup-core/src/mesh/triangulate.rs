//! Polygon triangulation: ear clipping in a polygon's best-fit plane ([`triangulate_polygon`]),
//! with its work bounded ([`triangulation_work_budget`]) and its failures named
//! ([`PolygonProblem`]).

use glam::{DVec2, DVec3};

/// Why a polygon gets no triangles from [`triangulate_polygon`] (it stays in
/// [`Mesh::polygons`](super::Mesh::polygons), so outputs keep it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum PolygonProblem {
    /// Fewer than 3 distinct vertices once repeated neighbouring corners are merged.
    #[error("fewer than 3 distinct corners")]
    TooFewCorners,
    /// A directed edge occurs twice: the polygon runs over itself the same way (a hole's
    /// bridge edge is run once each way, which is fine).
    #[error("the edge {0} → {1} occurs twice in the same direction (the polygon runs over itself)")]
    RepeatedEdge(u32, u32),
    /// Nothing is left once back-and-forth spikes (`a b a`) are removed.
    #[error("its corners only go back and forth (no area)")]
    NoArea,
    /// A corner names a vertex past the end of the positions.
    #[error("corner vertex {0} does not exist")]
    MissingVertex(u32),
}

/// What [`triangulate_polygon`] did with one polygon.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PolygonTriangulation {
    /// Triangles appended.
    pub triangles: usize,
    /// Elementary steps taken (corners classified, ear candidates, grid cells and points
    /// looked at): at most [`triangulation_work_budget`] of the corner count, plus one per
    /// corner for a final fan. Linear for convex and nearly convex polygons.
    pub work: usize,
    /// Whether a vertex occurs at two corners (a hole joined by a bridge edge, a pinch).
    pub repeated_corners: bool,
    /// Whether the work budget ran out (a self-intersecting or very irregular polygon) and
    /// what was left became a fan from one corner, whose triangles may overlap.
    pub fan_fallback: bool,
}

/// Ear clipping's work budget per corner (see [`triangulation_work_budget`]).
pub const TRIANGULATION_WORK_PER_CORNER: usize = 128;

/// Work every polygon may take whatever its size, so that polygons of up to a few hundred
/// corners are never cut short (about a millisecond).
pub const TRIANGULATION_WORK_FLOOR: usize = 1 << 20;

/// The most work [`triangulate_polygon`] spends on ear clipping a polygon of `corners`
/// corners before it fans out the rest: `128 · corners + 2²⁰` (about 0.25 s for 150,000
/// corners).
pub fn triangulation_work_budget(corners: usize) -> usize {
    corners.saturating_mul(TRIANGULATION_WORK_PER_CORNER).saturating_add(TRIANGULATION_WORK_FLOOR)
}

/// Buffers [`triangulate_polygon`] reuses from one polygon to the next.
#[derive(Debug, Clone, Default)]
pub struct TriangulationScratch {
    ring: Vec<u32>,
    keys: Vec<u64>,
    points: Vec<DVec2>,
    prev: Vec<usize>,
    next: Vec<usize>,
    turn: Vec<f64>,
    kind: Vec<Corner>,
    indexed: Vec<bool>,
    extra: Vec<usize>,
    cell_start: Vec<usize>,
    cell_items: Vec<usize>,
    blockers: Vec<usize>,
}

/// A corner of the ring being clipped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Corner {
    /// Turns left (towards the inside): a candidate ear.
    Convex,
    /// Goes straight on: neither an ear nor able to block one on its own.
    Flat,
    /// Turns right, turns back, or has a zero-length side: may lie inside an ear.
    Blocking,
    /// Already cut off.
    Removed,
}

/// Distance below which a point counts as on an ear's side, relative to the polygon's size.
const INSIDE_TOLERANCE: f64 = 1e-12;

/// Turn |e₁ × e₂| below which a corner counts as straight, relative to the polygon's size
/// times |e₁| + |e₂| (about ten times the rounding error of the projected coordinates).
const TURN_TOLERANCE: f64 = 1e-14;

/// Triangulates one polygon by ear clipping in its best-fit plane, appending its triangles
/// (same winding as the polygon) to `out`; `scratch` is reused between calls.
///
/// Repeated neighbouring corners (`a b b c`, also across the end) are merged and
/// back-and-forth spikes (`a b a`) removed first. A vertex may then still occur at two
/// corners: a hole joined to the outline by a bridge edge (outline `0 1 2 3`, hole `4 5 6 7`
/// written `0 1 2 3 0 4 7 6 5 4`, the hole the other way round), as LightWave and other
/// exporters write it, is triangulated around the hole. Fails, appending nothing, with the
/// reason when fewer than 3 distinct corners remain, when a directed edge occurs twice, or when
/// nothing is left after the spikes.
///
/// The plane's normal is Newell's, n = Σ_i (p_i − p_0) × (p_{i+1} − p_0) (the area vector of
/// the polygon, Newell 1972), which follows the polygon's winding; corners are projected onto
/// the plane and an *ear* — a convex corner whose triangle with its two neighbours contains no
/// other corner — is cut off until a triangle is left (Meisters 1975). Only corners that turn
/// right (or back) can lie in an ear's triangle when no edge crosses it (Eberly, "Triangulation
/// by ear clipping", 2002), so only those are tested, through a uniform grid; a corner at the
/// very position of the ear's own corners (the other end of a bridge) does not block it. The
/// search starts at the second corner; after each cut it goes on at the next corner when no
/// corner turns right, so a convex polygon (v₀, …, v_k) gives exactly the fan
/// (v₀, v_i, v_{i+1}), and one corner further otherwise, which keeps the ears small. No triangle of a
/// simple polygon, or of a hole joined by a bridge, folds over; for a self-intersecting or
/// degenerate polygon (no ear exists) the corner with the largest convex turn is cut. The work
/// is linear for convex and nearly convex polygons; after [`triangulation_work_budget`] steps
/// (a self-intersecting polygon of many corners), the rest becomes a fan from one corner and
/// [`PolygonTriangulation::fan_fallback`] says so.
///
/// # Errors
/// [`PolygonProblem`]: why the polygon got no triangles.
pub fn triangulate_polygon(
    positions: &[DVec3],
    polygon: &[u32],
    scratch: &mut TriangulationScratch,
    out: &mut Vec<[u32; 3]>,
) -> Result<PolygonTriangulation, PolygonProblem> {
    let s = scratch;
    if let Some(&v) = polygon.iter().find(|&&v| v as usize >= positions.len()) {
        return Err(PolygonProblem::MissingVertex(v));
    }
    reduce_ring(polygon, &mut s.ring);
    let k = s.ring.len();
    if k < 3 {
        // (A reduced ring of 3 or more corners has 3 distinct ones: neighbours differ, no spikes.)
        s.keys.clear();
        s.keys.extend(polygon.iter().map(|&v| u64::from(v)));
        s.keys.sort_unstable();
        s.keys.dedup();
        return Err(if s.keys.len() < 3 { PolygonProblem::TooFewCorners } else { PolygonProblem::NoArea });
    }
    let mut info = PolygonTriangulation { work: k, ..Default::default() };
    if k == 3 {
        out.push([s.ring[0], s.ring[1], s.ring[2]]);
        info.triangles = 1;
        return Ok(info);
    }
    // Repeated vertices, by sorting (k log k; a hash set would allocate for every polygon).
    s.keys.clear();
    s.keys.extend(s.ring.iter().map(|&v| u64::from(v)));
    s.keys.sort_unstable();
    info.repeated_corners = s.keys.windows(2).any(|w| w[0] == w[1]);
    if info.repeated_corners {
        s.keys.clear();
        s.keys.extend((0..k).map(|i| u64::from(s.ring[i]) << 32 | u64::from(s.ring[(i + 1) % k])));
        s.keys.sort_unstable();
        if let Some(w) = s.keys.windows(2).find(|w| w[0] == w[1]) {
            return Err(PolygonProblem::RepeatedEdge((w[0] >> 32) as u32, w[0] as u32));
        }
    }
    let before = out.len();
    // Best-fit plane: Newell's normal and a basis (u, w) with u × w = n.
    let p = |v: u32| positions[v as usize];
    let origin = p(s.ring[0]);
    let mut normal = DVec3::ZERO;
    for i in 1..k - 1 {
        normal += (p(s.ring[i]) - origin).cross(p(s.ring[i + 1]) - origin);
    }
    let normal = normal.normalize_or_zero();
    if normal == DVec3::ZERO {
        // No plane at all (every corner on one line, or the area cancels out): a fan.
        for i in 1..k - 1 {
            push_distinct(out, [s.ring[0], s.ring[i], s.ring[i + 1]]);
        }
    } else {
        let u = normal.any_orthonormal_vector();
        let w = normal.cross(u);
        s.points.clear();
        s.points.extend(s.ring.iter().map(|&v| {
            let d = p(v) - origin;
            DVec2::new(d.dot(u), d.dot(w))
        }));
        let mut clipper = Clipper::new(s, triangulation_work_budget(k));
        clipper.run(out);
        info.work = clipper.work;
        info.fan_fallback = clipper.fan_fallback;
    }
    info.triangles = out.len() - before;
    if info.triangles == 0 {
        return Err(PolygonProblem::NoArea);
    }
    Ok(info)
}

/// `polygon` with repeated neighbouring corners merged and back-and-forth spikes (`a b a` →
/// `a`) removed, also across the end, into `ring`. [O(k)]
fn reduce_ring(polygon: &[u32], ring: &mut Vec<u32>) {
    ring.clear();
    for &v in polygon {
        let n = ring.len();
        if ring.last() == Some(&v) {
            continue;
        }
        if n >= 2 && ring[n - 2] == v {
            ring.pop();
            continue;
        }
        ring.push(v);
    }
    // Across the end: the ring is ring[lo..hi].
    let (mut lo, mut hi) = (0, ring.len());
    while hi - lo >= 2 {
        if ring[lo] == ring[hi - 1] {
            hi -= 1;
        } else if hi - lo >= 3 && ring[hi - 2] == ring[lo] {
            hi -= 2;
        } else if hi - lo >= 3 && ring[hi - 1] == ring[lo + 1] {
            lo += 2;
        } else {
            break;
        }
    }
    ring.truncate(hi);
    ring.drain(..lo);
}

fn push_distinct(out: &mut Vec<[u32; 3]>, [a, b, c]: [u32; 3]) -> bool {
    let distinct = a != b && b != c && c != a;
    if distinct {
        out.push([a, b, c]);
    }
    distinct
}

/// Ear clipping over a linked ring of the projected corners in `TriangulationScratch`.
struct Clipper<'a> {
    s: &'a mut TriangulationScratch,
    head: usize,
    remaining: usize,
    work: usize,
    budget: usize,
    fan_fallback: bool,
    /// The polygon's size: the farthest corner from the first.
    turn_tolerance: f64,
    inside_tolerance: f64,
    /// The grid of blocking corners: lower corner, cells per unit, cells along x and y.
    grid_lo: DVec2,
    grid_scale: DVec2,
    grid_size: [usize; 2],
    /// Whether the grid is built (a corner that becomes blocking later goes to `extra`).
    ready: bool,
    /// Blocking corners in the ring now, and in the grid when it was built.
    live_blocking: usize,
    grid_population: usize,
}

impl<'a> Clipper<'a> {
    fn new(s: &'a mut TriangulationScratch, budget: usize) -> Self {
        let k = s.points.len();
        let size = s.points.iter().map(|q| q.length()).fold(0.0, f64::max);
        s.prev.clear();
        s.prev.extend((0..k).map(|i| (i + k - 1) % k));
        s.next.clear();
        s.next.extend((0..k).map(|i| (i + 1) % k));
        s.turn.clear();
        s.turn.resize(k, 0.0);
        s.kind.clear();
        s.kind.resize(k, Corner::Convex);
        s.indexed.clear();
        s.indexed.resize(k, false);
        s.extra.clear();
        s.cell_start.clear();
        s.cell_items.clear();
        let mut clipper = Clipper {
            s,
            head: 0,
            remaining: k,
            work: k,
            budget,
            fan_fallback: false,
            turn_tolerance: TURN_TOLERANCE * size,
            inside_tolerance: INSIDE_TOLERANCE * size,
            grid_lo: DVec2::ZERO,
            grid_scale: DVec2::ZERO,
            grid_size: [1, 1],
            ready: false,
            live_blocking: 0,
            grid_population: 0,
        };
        for i in 0..k {
            clipper.classify(i);
        }
        clipper.build_grid();
        clipper.ready = true;
        clipper
    }

    /// Sets the turn and kind of corner `i` from its current neighbours; a corner that becomes
    /// blocking after the grid was built goes to the extra list.
    fn classify(&mut self, i: usize) {
        let s = &mut *self.s;
        let (a, b, c) = (s.points[s.prev[i]], s.points[i], s.points[s.next[i]]);
        let (e1, e2) = (b - a, c - b);
        let turn = e1.perp_dot(e2);
        let tolerance = self.turn_tolerance * (e1.length() + e2.length());
        s.turn[i] = turn;
        let was = s.kind[i];
        s.kind[i] = if turn > tolerance {
            Corner::Convex
        } else if turn >= -tolerance && e1.dot(e2) > 0.0 {
            Corner::Flat
        } else {
            Corner::Blocking
        };
        match (was == Corner::Blocking, s.kind[i] == Corner::Blocking) {
            (false, true) => self.live_blocking += 1,
            (true, false) => self.live_blocking -= 1,
            _ => {}
        }
        if self.ready && s.kind[i] == Corner::Blocking && !s.indexed[i] {
            s.indexed[i] = true;
            s.extra.push(i);
        }
    }

    /// A uniform grid over the blocking corners, about one cell per corner (counting sort
    /// into `cell_start` / `cell_items`). Built at the start from every blocking corner, and
    /// again from those still blocking once half of them no longer are (cutting ears turns
    /// reflex corners convex), so that a grid never holds mostly dead entries: each rebuild
    /// costs its entries, which halve, so all rebuilds together cost O(k).
    fn build_grid(&mut self) {
        let s = &mut *self.s;
        // The corners to hold: at the start every blocking one, later the grid's and the
        // extra list's that still block.
        let mut items = std::mem::take(&mut s.blockers);
        items.clear();
        if s.cell_start.is_empty() && s.extra.is_empty() && !self.ready {
            items.extend((0..s.kind.len()).filter(|&i| s.kind[i] == Corner::Blocking));
        } else {
            for &i in s.cell_items.iter().chain(&s.extra) {
                s.indexed[i] = false;
                if s.kind[i] == Corner::Blocking {
                    items.push(i);
                }
            }
        }
        self.work += s.cell_items.len() + s.extra.len() + items.len();
        s.cell_start.clear();
        s.cell_items.clear();
        s.extra.clear();
        let blocking = items.len();
        self.grid_population = blocking;
        if blocking == 0 {
            s.blockers = items;
            return;
        }
        let (lo, hi) = items
            .iter()
            .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &i| (lo.min(s.points[i]), hi.max(s.points[i])));
        let extent = hi - lo;
        let cell = (extent.x * extent.y / blocking as f64).sqrt();
        let count = |length: f64| {
            let n = (length / cell).ceil();
            // Also NaN (a zero extent) → 1 cell.
            if n >= 1.0 { (n as usize).min(blocking) } else { 1 }
        };
        let (nx, ny) = (count(extent.x), count(extent.y));
        self.grid_lo = lo;
        self.grid_scale = DVec2::new(
            if extent.x > 0.0 { nx as f64 / extent.x } else { 0.0 },
            if extent.y > 0.0 { ny as f64 / extent.y } else { 0.0 },
        );
        self.grid_size = [nx, ny];
        s.cell_start.resize(nx * ny + 2, 0);
        for &i in &items {
            s.cell_start[cell_of(lo, self.grid_scale, self.grid_size, s.points[i]) + 2] += 1;
            s.indexed[i] = true;
        }
        for c in 2..nx * ny + 2 {
            s.cell_start[c] += s.cell_start[c - 1];
        }
        // cell_start[c + 1] is where cell c's items go; after filling, where cell c + 1's start.
        s.cell_items.resize(blocking, 0);
        for &i in &items {
            let c = cell_of(lo, self.grid_scale, self.grid_size, s.points[i]);
            s.cell_items[s.cell_start[c + 1]] = i;
            s.cell_start[c + 1] += 1;
        }
        s.cell_start.pop();
        s.blockers = items;
    }

    /// Whether a blocking corner lies in the triangle (a, b, c) of corners `ia`, `ib`, `ic`
    /// (within the tolerance; a corner at the very position of one of the three does not
    /// count). Also `true` once the work budget is spent.
    fn blocked(&mut self, ia: usize, ib: usize, ic: usize) -> bool {
        let s = &*self.s;
        let (a, b, c) = (s.points[ia], s.points[ib], s.points[ic]);
        let t = self.inside_tolerance;
        let (lab, lbc, lca) = ((b - a).length() * t, (c - b).length() * t, (a - c).length() * t);
        let lo = a.min(b).min(c) - DVec2::splat(t);
        let hi = a.max(b).max(c) + DVec2::splat(t);
        let blocks = |q: usize| {
            let p = s.points[q];
            s.kind[q] == Corner::Blocking
                && q != ia
                && q != ib
                && q != ic
                && p.cmpge(lo).all()
                && p.cmple(hi).all()
                && p != a
                && p != b
                && p != c
                && (b - a).perp_dot(p - a) >= -lab
                && (c - b).perp_dot(p - b) >= -lbc
                && (a - c).perp_dot(p - c) >= -lca
        };
        // The cells the triangle covers, row by row (a sliver crosses few of them, where its
        // bounding box may hold most of the grid).
        let [nx, _] = self.grid_size;
        let row_of =
            |y: f64| cell_of(self.grid_lo, self.grid_scale, self.grid_size, DVec2::new(self.grid_lo.x, y)) / nx;
        let rows = if s.cell_start.is_empty() { None } else { Some(row_of(lo.y)..=row_of(hi.y)) };
        for row in rows.into_iter().flatten() {
            let (band_lo, band_hi) = if self.grid_scale.y > 0.0 {
                let h = 1.0 / self.grid_scale.y;
                (self.grid_lo.y + row as f64 * h - t, self.grid_lo.y + (row + 1) as f64 * h + t)
            } else {
                (f64::NEG_INFINITY, f64::INFINITY)
            };
            let Some((x_lo, x_hi)) = x_range_in_band([a, b, c], band_lo, band_hi) else { continue };
            let first = cell_of(self.grid_lo, self.grid_scale, self.grid_size, DVec2::new(x_lo - t, self.grid_lo.y));
            let last = cell_of(self.grid_lo, self.grid_scale, self.grid_size, DVec2::new(x_hi + t, self.grid_lo.y));
            for cell in row * nx + first..=row * nx + last {
                self.work += 1 + s.cell_start[cell + 1] - s.cell_start[cell];
                if s.cell_items[s.cell_start[cell]..s.cell_start[cell + 1]].iter().any(|&q| blocks(q)) {
                    return true;
                }
                if self.work > self.budget {
                    return true;
                }
            }
        }
        self.work += s.extra.len();
        s.extra.iter().any(|&q| blocks(q))
    }

    fn is_ear(&mut self, b: usize) -> bool {
        let (a, c) = (self.s.prev[b], self.s.next[b]);
        self.s.kind[b] == Corner::Convex && self.s.ring[a] != self.s.ring[c] && !self.blocked(a, b, c)
    }

    fn unlink(&mut self, i: usize) {
        let s = &mut *self.s;
        let (p, n) = (s.prev[i], s.next[i]);
        s.next[p] = n;
        s.prev[n] = p;
        if s.kind[i] == Corner::Blocking {
            self.live_blocking -= 1;
        }
        s.kind[i] = Corner::Removed;
        if self.head == i {
            self.head = n;
        }
        self.remaining -= 1;
    }

    /// Cuts corner `b` off (its triangle, unless two of its corners are one vertex), then
    /// removes spikes (`a b a`) this leaves. Returns a corner still in the ring near `b`.
    fn cut(&mut self, b: usize, out: &mut Vec<[u32; 3]>) -> usize {
        let (a, c) = (self.s.prev[b], self.s.next[b]);
        push_distinct(out, [self.s.ring[a], self.s.ring[b], self.s.ring[c]]);
        self.unlink(b);
        self.classify(a);
        self.classify(c);
        let mut pending = [Some(a), Some(c)];
        let mut keep = a;
        while let Some(i) = pending.iter_mut().find_map(Option::take) {
            let s = &*self.s;
            if s.kind[i] == Corner::Removed || self.remaining < 3 || s.ring[s.prev[i]] != s.ring[s.next[i]] {
                continue;
            }
            // `i` is a spike's tip: drop it and the second copy of its neighbour.
            let (p, n) = (s.prev[i], s.next[i]);
            self.unlink(i);
            self.unlink(n);
            self.classify(p);
            let after = self.s.next[p];
            self.classify(after);
            pending = [Some(p), Some(after)];
            keep = p;
        }
        keep
    }

    fn run(&mut self, out: &mut Vec<[u32; 3]>) {
        // Without a reflex corner every convex corner is an ear: going on at the next corner
        // after each cut gives the fan from the first corner. With one, going on one corner
        // further keeps the ears small (as earcut does): a fan's slivers would cross the whole
        // grid, the next round's ears span two of this round's, and so on.
        let skip = self.live_blocking > 0;
        let mut current = self.s.next[self.head];
        let mut stop = current;
        while self.remaining > 3 {
            if self.work > self.budget {
                self.fan_fallback = true;
                break;
            }
            self.work += 1;
            if self.grid_population >= 16 && 2 * self.live_blocking < self.grid_population
                || self.s.extra.len() > self.grid_population.max(16)
            {
                self.build_grid();
            }
            if self.is_ear(current) {
                let kept = self.cut(current, out);
                current = self.s.next[kept];
                if skip && self.remaining > 3 {
                    current = self.s.next[current];
                }
                stop = current;
                continue;
            }
            current = self.s.next[current];
            if current == stop {
                // A full turn without an ear: cut the corner with the largest convex turn.
                let mut best = (self.s.next[self.head], f64::NEG_INFINITY);
                let mut i = self.head;
                for _ in 0..self.remaining {
                    if self.s.turn[i] > best.1 {
                        best = (i, self.s.turn[i]);
                    }
                    i = self.s.next[i];
                }
                self.work += self.remaining;
                let kept = self.cut(best.0, out);
                current = self.s.next[kept];
                stop = current;
            }
        }
        // The last triangle, or the fan of what the budget left.
        if self.remaining >= 3 {
            let s = &*self.s;
            let mut i = s.next[self.head];
            while s.next[i] != self.head {
                push_distinct(out, [s.ring[self.head], s.ring[i], s.ring[s.next[i]]]);
                i = s.next[i];
                self.work += 1;
            }
        }
    }
}

/// The x-range of the triangle's part with y in [lo, hi], or `None` if it has none there.
fn x_range_in_band(corners: [DVec2; 3], lo: f64, hi: f64) -> Option<(f64, f64)> {
    let mut range = (f64::INFINITY, f64::NEG_INFINITY);
    let mut take = |x: f64| range = (range.0.min(x), range.1.max(x));
    for (i, &p) in corners.iter().enumerate() {
        if (lo..=hi).contains(&p.y) {
            take(p.x);
        }
        let q = corners[(i + 1) % 3];
        for y in [lo, hi] {
            if (p.y < y) != (q.y < y) {
                take(p.x + (y - p.y) / (q.y - p.y) * (q.x - p.x));
            }
        }
    }
    (range.0 <= range.1).then_some(range)
}

/// The grid cell holding `q` (clamped to the grid).
fn cell_of(lo: DVec2, scale: DVec2, [nx, ny]: [usize; 2], q: DVec2) -> usize {
    // `as` saturates: negative and NaN → 0.
    let x = (((q.x - lo.x) * scale.x) as usize).min(nx - 1);
    let y = (((q.y - lo.y) * scale.y) as usize).min(ny - 1);
    y * nx + x
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::mesh::{Mesh, Polygons};

    fn polys(list: &[&[u32]]) -> Polygons {
        list.iter().copied().collect()
    }

    fn area_vector(positions: &[DVec3], t: [u32; 3]) -> DVec3 {
        let p = t.map(|v| positions[v as usize]);
        0.5 * (p[1] - p[0]).cross(p[2] - p[0])
    }

    #[test]
    fn concave_quad_is_cut_along_its_inner_diagonal() {
        // An arrowhead: corner 3 points inwards, so the fan from 0 (diagonal 0–2) would fold over.
        let positions =
            vec![DVec3::ZERO, DVec3::new(2.0, 1.0, 0.0), DVec3::new(0.0, 2.0, 0.0), DVec3::new(0.5, 1.0, 0.0)];
        let (mesh, _) = Mesh::from_polygons(positions.clone(), polys(&[&[0, 1, 2, 3]])).unwrap();
        let total: DVec3 = mesh.triangles.iter().map(|&t| area_vector(&positions, t)).sum();
        assert!((total.z - 1.5).abs() < 1e-12, "area {total}");
        for &t in &mesh.triangles {
            assert!(area_vector(&positions, t).z > 0.0, "triangle {t:?} folds over");
        }
    }

    #[test]
    fn l_shaped_hexagon_in_a_tilted_plane_has_no_folded_triangle() {
        let flat = [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 1.0), (1.0, 2.0), (0.0, 2.0)];
        let turn = glam::DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let positions: Vec<DVec3> = flat.iter().map(|&(x, y)| turn * DVec3::new(x, y, 0.0)).collect();
        // Start the polygon at the reflex corner's neighbour so that a fan would fold.
        let (mesh, _) = Mesh::from_polygons(positions.clone(), polys(&[&[4, 5, 0, 1, 2, 3]])).unwrap();
        assert_eq!(mesh.triangles.len(), 4);
        let normal = turn * DVec3::Z;
        let mut area = 0.0;
        for &t in &mesh.triangles {
            let a = area_vector(&positions, t);
            assert!(a.dot(normal) > 1e-9, "triangle {t:?} folds over or is degenerate");
            area += a.dot(normal);
        }
        assert!((area - 3.0).abs() < 1e-12, "the triangles tile the polygon: area {area}");
    }

    #[test]
    fn random_simple_polygons_triangulate_without_folds() {
        // Star-shaped polygons with random radii are simple; every ear-clipped triangle must
        // turn the same way as the polygon and the areas must add up.
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for k in 4..40 {
            let positions: Vec<DVec3> = (0..k)
                .map(|i| {
                    let a = std::f64::consts::TAU * i as f64 / k as f64;
                    let r = 0.2 + next();
                    DVec3::new(r * a.cos(), r * a.sin(), 0.0)
                })
                .collect();
            let area: f64 =
                (0..k).map(|i| positions[i].truncate().perp_dot(positions[(i + 1) % k].truncate())).sum::<f64>() / 2.0;
            let poly: Vec<u32> = (0..k as u32).collect();
            let mut out = Vec::new();
            assert!(triangulate_polygon(&positions, &poly, &mut TriangulationScratch::default(), &mut out).is_ok());
            assert_eq!(out.len(), k - 2);
            let sum: f64 = out.iter().map(|&t| area_vector(&positions, t).z).sum();
            assert!(out.iter().all(|&t| area_vector(&positions, t).z > 0.0), "k = {k}: a triangle folds");
            assert!((sum - area).abs() < 1e-12 * area.abs().max(1.0), "k = {k}: {sum} vs {area}");
        }
    }
}
