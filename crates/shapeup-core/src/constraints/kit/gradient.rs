//! Deformation gradients of rest elements as rows of C: [`TriangleGradient`] (3×2, strain and
//! area) and [`TetGradient`] (3×3, strain and volume).

use crate::constraints::contract::RowSink;
use crate::geometry::{is_degenerate_triangle, tet_volume};
use glam::{DMat2, DMat3, DVec2, DVec3};

/// Smallest rest area that gets a constraint (smaller triangles are skipped).
const MIN_REST_AREA: f64 = 1e-12;
/// Smallest rest volume that gets a constraint (smaller tetrahedra are skipped).
const MIN_REST_VOLUME: f64 = 1e-12;

/// The deformation gradient T = [q_b − q_a, q_c − q_a] D⁻¹ (3×2) of a rest triangle (a, b,
/// c): its rows of C and the current frame its projections are computed in. Shared by the
/// triangle types (strain, area).
#[derive(Debug, Clone)]
pub(crate) struct TriangleGradient {
    pub(crate) vertices: [u32; 3],
    /// D⁻¹ (2×2): column k holds the coefficients of (q_b − q_a, q_c − q_a) in T's column k.
    rest_inverse: DMat2,
    /// P⁰'s columns, the frame used when the current triangle has collapsed to a point.
    pub(crate) rest_frame: [DVec3; 2],
    /// The rest area A_t.
    pub(crate) rest_area: f64,
}

impl TriangleGradient {
    /// The gradient of triangle (a, b, c) of the rest shape `rest`; `None` if the rest
    /// triangle is degenerate ([`is_degenerate_triangle`] or area ≤ 1e-12, or not a number).
    ///
    /// P⁰ = [t, n̂ × t] with t = (x⁰_b − x⁰_a)/‖x⁰_b − x⁰_a‖ and n̂ the unit rest normal, so
    /// D = [[‖e₁‖, t·e₂], [0, (n̂ × t)·e₂]] is upper triangular with det D = 2A_t > 0.
    pub(crate) fn new(vertices: [u32; 3], rest: &[DVec3]) -> Option<Self> {
        let [a, b, c] = vertices.map(|v| rest[v as usize]);
        let (e1, e2) = (b - a, c - a);
        let normal = e1.cross(e2);
        let area = 0.5 * normal.length();
        if is_degenerate_triangle(a, b, c) || area.is_nan() || area <= MIN_REST_AREA {
            return None;
        }
        let t = e1.normalize();
        let s = normal.normalize().cross(t);
        let d = DMat2::from_cols(DVec2::new(t.dot(e1), s.dot(e1)), DVec2::new(t.dot(e2), s.dot(e2)));
        Some(TriangleGradient { vertices, rest_inverse: d.inverse(), rest_frame: [t, s], rest_area: area })
    }

    /// The two rows of C (T's columns).
    pub(crate) fn rows(&self, sink: &mut RowSink) {
        let [a, b, c] = self.vertices;
        for (k, col) in [self.rest_inverse.x_axis, self.rest_inverse.y_axis].into_iter().enumerate() {
            sink.push(k, a, -(col.x + col.y));
            sink.push(k, b, col.x);
            sink.push(k, c, col.y);
        }
    }

    /// T = [q_b − q_a, q_c − q_a] D⁻¹, as its two columns.
    #[inline]
    pub(crate) fn at(&self, q: &[DVec3]) -> [DVec3; 2] {
        let [a, b, c] = self.vertices.map(|v| q[v as usize]);
        let (e1, e2) = (b - a, c - a);
        let m = self.rest_inverse;
        [e1 * m.x_axis.x + e2 * m.x_axis.y, e1 * m.y_axis.x + e2 * m.y_axis.y]
    }

    /// An orthonormal frame (u, v) of the plane of T's columns with `det [u v]ᵀT ≥ 0`: u along
    /// the longer column, v = (n × u)/‖n × u‖ with n = t₀ × t₁. A collapsed triangle (rank 1)
    /// gets any v ⊥ u; one collapsed to a point gets the rest frame.
    #[inline]
    pub(crate) fn current_frame(&self, t: &[DVec3; 2]) -> [DVec3; 2] {
        let (l0, l1) = (t[0].length_squared(), t[1].length_squared());
        let (long, l) = if l0 >= l1 { (t[0], l0) } else { (t[1], l1) };
        if l.is_nan() || l <= 1e-300 {
            return self.rest_frame;
        }
        let u = long / l.sqrt();
        let n = t[0].cross(t[1]);
        // n is pure rounding noise below ~1e-16 ‖t₀‖‖t₁‖: then any v ⊥ u will do.
        let v = if n.length_squared() > 1e-24 * l0 * l1 {
            n.cross(u).normalize_or(u.any_orthonormal_vector())
        } else {
            u.any_orthonormal_vector()
        };
        [u, v]
    }

    /// [u v]ᵀ T: T in the frame (u, v) of [`TriangleGradient::current_frame`].
    #[inline]
    pub(crate) fn in_frame([u, v]: [DVec3; 2], t: &[DVec3; 2]) -> DMat2 {
        DMat2::from_cols(DVec2::new(u.dot(t[0]), v.dot(t[0])), DVec2::new(u.dot(t[1]), v.dot(t[1])))
    }

    /// The columns of [u v] p: a 2×2 matrix in the frame (u, v) back in 3D, into `out`.
    #[inline]
    pub(crate) fn out_of_frame([u, v]: [DVec3; 2], p: DMat2, out: &mut [DVec3]) {
        out[0] = u * p.x_axis.x + v * p.x_axis.y;
        out[1] = u * p.y_axis.x + v * p.y_axis.y;
    }
}

/// The deformation gradient T = [q_b − q_a, q_c − q_a, q_d − q_a] D⁻¹ of a rest tetrahedron
/// (a, b, c, d) and its rows of C. Shared by the tetrahedron types (strain, volume).
#[derive(Debug, Clone)]
pub(crate) struct TetGradient {
    pub(crate) vertices: [u32; 4],
    /// D⁻¹: column k holds the coefficients of (q_b − q_a, q_c − q_a, q_d − q_a) in T's column k.
    rest_inverse: DMat3,
    /// The rest volume |V_T|.
    pub(crate) rest_volume: f64,
}

impl TetGradient {
    /// The gradient of tetrahedron (a, b, c, d) of the rest shape `rest`; `None` if its rest
    /// volume |V_T| is ≤ 1e-12. Either orientation of the rest tetrahedron works (T = I at rest).
    pub(crate) fn new(vertices: [u32; 4], rest: &[DVec3]) -> Option<Self> {
        Self::with_min_volume(vertices, rest, MIN_REST_VOLUME)
    }

    /// [`TetGradient::new`] with another least volume (a material in metres scales it with
    /// the tetrahedron's size instead).
    pub(crate) fn with_min_volume(vertices: [u32; 4], rest: &[DVec3], min_volume: f64) -> Option<Self> {
        let [a, b, c, d] = vertices.map(|v| rest[v as usize]);
        let volume = tet_volume(a, b, c, d).abs();
        if volume.is_nan() || volume <= min_volume {
            return None;
        }
        let rest_inverse = DMat3::from_cols(b - a, c - a, d - a).inverse();
        Some(TetGradient { vertices, rest_inverse, rest_volume: volume })
    }

    /// T = [q_b − q_a, q_c − q_a, q_d − q_a] D⁻¹.
    #[inline]
    pub(crate) fn at(&self, q: &[DVec3]) -> DMat3 {
        let [a, b, c, d] = self.vertices.map(|v| q[v as usize]);
        DMat3::from_cols(b - a, c - a, d - a) * self.rest_inverse
    }

    /// The three rows of C (T's columns).
    pub(crate) fn rows(&self, sink: &mut RowSink) {
        let [a, b, c, d] = self.vertices;
        let m = self.rest_inverse;
        for (k, col) in [m.x_axis, m.y_axis, m.z_axis].into_iter().enumerate() {
            sink.push(k, a, -(col.x + col.y + col.z));
            sink.push(k, b, col.x);
            sink.push(k, c, col.y);
            sink.push(k, d, col.z);
        }
    }
}
