//! Micro-benchmarks of the local step's small dense kernels against nalgebra.
//!
//! Each benchmark runs a kernel over a batch of 1024 matrices; criterion reports the batch time
//! and the throughput (elements/s); ns per call = batch time / 1024.
//!
//! Inputs: "near_rotation": `R (I + 0.3 G)`, G uniform in [−1, 1] (deformation gradients of a
//! tet mesh, det > 0); "one_ring": `S = Σⱼ eⱼ e⁰ⱼᵀ` of a jittered planar 6-ring under a random
//! rotation and a mild deformation (rank ≈ 2, the iso one-ring's input); "inverted": near
//! rotations with one column negated (det < 0).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{DMat2, DMat3, DQuat, DVec2, DVec3};
use shapeup_core::linalg;
use std::hint::black_box;

const BATCH: usize = 1024;

#[path = "../tests/common/rng.rs"]
mod rng;
use rng::Rng;

impl Rng {
    fn mat3(&mut self) -> DMat3 {
        DMat3::from_cols(self.vec3(), self.vec3(), self.vec3())
    }
    fn rotation(&mut self) -> DMat3 {
        let q = DQuat::from_xyzw(self.uniform(), self.uniform(), self.uniform(), self.uniform());
        DMat3::from_quat(q.normalize())
    }
}

fn near_rotation(rng: &mut Rng) -> DMat3 {
    let g = rng.mat3();
    rng.rotation() * (DMat3::IDENTITY + 0.3 * g)
}

fn one_ring(rng: &mut Rng) -> DMat3 {
    let rot = rng.rotation();
    let deform = DMat3::IDENTITY + 0.1 * rng.mat3();
    let mut s = DMat3::ZERO;
    for k in 0..6 {
        let t = k as f64 / 6.0 * std::f64::consts::TAU + 0.2 * rng.uniform();
        let r = 0.01 * (1.0 + 0.2 * rng.uniform());
        let e0 = DVec3::new(t.cos() * r, t.sin() * r, 0.001 * rng.uniform() * r);
        let e = rot * deform * e0;
        s += DMat3::from_cols(e * e0.x, e * e0.y, e * e0.z);
    }
    s
}

fn inverted(rng: &mut Rng) -> DMat3 {
    let mut m = DMat3::IDENTITY + 0.3 * rng.mat3();
    m.z_axis = -m.z_axis;
    rng.rotation() * m
}

fn to_na(m: &DMat3) -> nalgebra::Matrix3<f64> {
    nalgebra::Matrix3::from_column_slice(&m.to_cols_array())
}

/// nalgebra's nearest rotation: SVD, then `U diag(1, 1, det(UVᵀ)) Vᵀ`.
fn nalgebra_rotation(m: &nalgebra::Matrix3<f64>) -> nalgebra::Matrix3<f64> {
    let svd = m.svd(true, true);
    match (svd.u, svd.v_t) {
        (Some(u), Some(vt)) => {
            let d = (u * vt).determinant().signum();
            u * nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, d)) * vt
        }
        _ => nalgebra::Matrix3::identity(),
    }
}

fn bench_3x3(c: &mut Criterion) {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let inputs: [(&str, Vec<DMat3>); 3] = [
        ("near_rotation", (0..BATCH).map(|_| near_rotation(&mut rng)).collect()),
        ("one_ring", (0..BATCH).map(|_| one_ring(&mut rng)).collect()),
        ("inverted", (0..BATCH).map(|_| inverted(&mut rng)).collect()),
    ];
    for (name, mats) in &inputs {
        let na: Vec<_> = mats.iter().map(to_na).collect();
        let mut group = c.benchmark_group(format!("3x3/{name}"));
        group.throughput(Throughput::Elements(BATCH as u64));
        group.bench_function("nearest_rotation3", |b| {
            b.iter(|| mats.iter().map(|m| linalg::nearest_rotation3(black_box(*m))).fold(DMat3::ZERO, |a, r| a + r))
        });
        group.bench_function("nearest_rotation3_svd", |b| {
            b.iter(|| mats.iter().map(|m| linalg::nearest_rotation3_svd(black_box(*m))).fold(DMat3::ZERO, |a, r| a + r))
        });
        group.bench_function("svd3", |b| {
            b.iter(|| mats.iter().map(|m| linalg::svd3(black_box(*m)).sigma).fold(DVec3::ZERO, |a, s| a + s))
        });
        group.bench_function("nalgebra_svd", |b| {
            b.iter(|| na.iter().map(|m| black_box(*m).svd(true, true).singular_values).fold(0.0, |a, s| a + s[2]))
        });
        group.bench_function("nalgebra_rotation", |b| {
            b.iter(|| na.iter().map(|m| nalgebra_rotation(&black_box(*m))).fold(0.0, |a, r| a + r[(0, 0)]))
        });
        group.finish();
    }
}

fn bench_2x2(c: &mut Criterion) {
    let mut rng = Rng(7);
    let mats: Vec<DMat2> = (0..BATCH)
        .map(|_| {
            let g =
                DMat2::from_cols(DVec2::new(rng.uniform(), rng.uniform()), DVec2::new(rng.uniform(), rng.uniform()));
            DMat2::from_angle(3.0 * rng.uniform()) * (DMat2::IDENTITY + 0.3 * g)
        })
        .collect();
    let na: Vec<_> = mats.iter().map(|m| nalgebra::Matrix2::from_column_slice(&m.to_cols_array())).collect();
    let mut group = c.benchmark_group("2x2");
    group.throughput(Throughput::Elements(BATCH as u64));
    group.bench_function("nearest_rotation2", |b| {
        b.iter(|| mats.iter().map(|m| linalg::nearest_rotation2(black_box(*m))).fold(DMat2::ZERO, |a, r| a + r))
    });
    group.bench_function("svd2", |b| {
        b.iter(|| mats.iter().map(|m| linalg::svd2(black_box(*m)).sigma).fold(DVec2::ZERO, |a, s| a + s))
    });
    group.bench_function("clamp_singular_values2", |b| {
        b.iter(|| {
            mats.iter().map(|m| linalg::clamp_singular_values2(black_box(*m), 0.9, 1.1)).fold(DMat2::ZERO, |a, r| a + r)
        })
    });
    group.bench_function("nalgebra_svd", |b| {
        b.iter(|| na.iter().map(|m| black_box(*m).svd(true, true).singular_values).fold(0.0, |a, s| a + s[1]))
    });
    group.finish();
}

criterion_group!(benches, bench_3x3, bench_2x2);
criterion_main!(benches);
