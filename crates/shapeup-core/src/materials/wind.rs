//! Wind: the air's force on each triangle of a surface through its relative velocity, in a
//! simulation.
//!
//! For a triangle of current area A and unit normal n, moving at the mean v_t of its corners'
//! velocities in a wind of velocity w, the air meets it at u = w − v_t. With û = u/‖u‖ and
//! n oriented so that cos θ = n·û ≥ 0 (a face has two sides), the usual aerodynamic face model
//! (Keckeisen, Kimmerle, Thomaszewski and Wacker, "Modelling Effects of Wind Fields in Cloth
//! Animations", WSCG 2004) gives
//!
//!   drag  f_D = ½ ρ C_D A cos θ ‖u‖² û,
//!   lift  f_L = ½ ρ C_L A cos θ ‖u‖² l̂,  l̂ = (n − cos θ û)/‖n − cos θ û‖ (0 when n ∥ û),
//!
//! ρ the air's density (kg/m³), C_D and C_L the drag and lift coefficients; A cos θ is the
//! area the flow sees, and l̂ the part of the normal across the flow (the side the air pushes
//! the face to). A third of f_D + f_L goes to each corner. The force depends on
//! velocities, so it is not the gradient of an energy: time stepping applies it explicitly,
//! from the positions and velocities at the start of each step, as it does gravity. A falling
//! horizontal sheet reaches the terminal velocity where drag balances its weight,
//! v = √(2 m g / (ρ C_D A)) (the tests check it).

use glam::DVec3;

/// The wind and the air ([module docs](self)), in the working frame (metres, m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wind {
    /// w, the air's velocity far from the surface (m/s).
    pub velocity: DVec3,
    /// C_D, the drag coefficient (a flat plate across the flow: about 1.2).
    pub drag: f64,
    /// C_L, the lift coefficient.
    pub lift: f64,
    /// ρ, the air's density (kg/m³; 1.225 at sea level, 15 °C).
    pub air_density: f64,
}

/// The wind's force on each vertex of `triangles` at `positions` moving at `velocities`,
/// added into `forces` (N; the caller zeroes it).
pub fn add_wind_forces(
    wind: &Wind,
    triangles: &[[u32; 3]],
    positions: &[DVec3],
    velocities: &[DVec3],
    forces: &mut [DVec3],
) {
    for t in triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let twice_area = (b - a).cross(c - a);
        let area = 0.5 * twice_area.length();
        let v = t.iter().map(|&i| velocities[i as usize]).sum::<DVec3>() / 3.0;
        let u = wind.velocity - v;
        let speed = u.length();
        if area == 0.0 || speed == 0.0 || !area.is_finite() || !speed.is_finite() {
            continue;
        }
        let (n, along) = (twice_area / (2.0 * area), u / speed);
        let n = if n.dot(along) < 0.0 { -n } else { n };
        let seen = 0.5 * wind.air_density * area * n.dot(along) * speed * speed;
        let lift_direction = (n - n.dot(along) * along).normalize_or_zero();
        let force = seen * (wind.drag * along + wind.lift * lift_direction);
        for &i in t {
            forces[i as usize] += force / 3.0;
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    fn forces(wind: &Wind, positions: &[DVec3], velocities: &[DVec3]) -> Vec<DVec3> {
        let mut out = vec![DVec3::ZERO; 3];
        add_wind_forces(wind, &[[0, 1, 2]], positions, velocities, &mut out);
        out
    }

    #[test]
    fn a_plate_across_the_flow_feels_half_rho_cd_a_u_squared_along_it_either_side() {
        // A triangle of area 0.5 m² in the plane y = 0, wind 10 m/s along −y.
        let p = [DVec3::ZERO, DVec3::X, DVec3::Z];
        let wind = Wind { velocity: DVec3::new(0.0, -10.0, 0.0), drag: 1.2, lift: 0.7, air_density: 1.225 };
        let f: DVec3 = forces(&wind, &p, &[DVec3::ZERO; 3]).iter().sum();
        let expected = 0.5 * 1.225 * 1.2 * 0.5 * 100.0;
        assert!((f - DVec3::new(0.0, -expected, 0.0)).length() < 1e-12, "{f}, no lift head-on");
        // Turned over, the same force; moving with the wind, none.
        let turned = [p[0], p[2], p[1]];
        let g: DVec3 = forces(&wind, &turned, &[DVec3::ZERO; 3]).iter().sum();
        assert!((g - f).length() < 1e-12);
        let none: DVec3 = forces(&wind, &p, &[wind.velocity; 3]).iter().sum();
        assert_eq!(none, DVec3::ZERO);
    }

    #[test]
    fn an_inclined_plate_feels_drag_along_the_flow_and_lift_across_it() {
        // The plate's normal at 60° to the flow (along +x): cos θ = ½.
        let n = DVec3::new(0.5, 3f64.sqrt() / 2.0, 0.0);
        let e1 = DVec3::Z;
        let e2 = n.cross(e1);
        let p = [DVec3::ZERO, e2, e1];
        let wind = Wind { velocity: DVec3::new(4.0, 0.0, 0.0), drag: 1.0, lift: 0.5, air_density: 1.0 };
        let f: DVec3 = forces(&wind, &p, &[DVec3::ZERO; 3]).iter().sum();
        let seen = 0.5 * 1.0 * 0.5 * 0.5 * 16.0;
        assert!((f.x - seen).abs() < 1e-12, "drag along the flow: {f}");
        assert!((f.y - 0.5 * seen).abs() < 1e-12 && f.z.abs() < 1e-12, "lift across it, to the normal's side: {f}");
        // Each corner a third.
        let each = forces(&wind, &p, &[DVec3::ZERO; 3]);
        assert!(each.iter().all(|g| (*g * 3.0 - f).length() < 1e-12));
    }
}
