//! The checks of the four-point pose with unknown focal length: its generated quadrics against
//! the projection matrix's Gram matrix computed numerically, the generated E3Q3 elimination
//! (the octic against the LU determinant of its own matrix `L`, a planted solution as a root
//! and a null vector), the three-quadric solver against an independent count (the companion
//! matrix's real roots of the octic with another variable hidden), and the P4Pf solver (the true
//! pose and focal length among its solutions).
//!
//! Random P4Pf instances: a focal length log-uniform in 300 to 3,000 px, a random rotation and a
//! translation of a unit or so, four points 2 to 10 units in front of the camera within a field
//! of view of about 53 x 43 degrees, pixels relative to the principal point; those whose world
//! points are less than 1 % out of coplanarity (the planar solver's domain) are redrawn.

use super::companion_roots;

use crate::report::{Measurement, Tracker};
use crate::strategies as st;
use eopnp::internals::kernels as k;
use eopnp::internals::metrics::rotation_error_deg;
use eopnp::internals::p4pf::{e3q3, p4pf};
use nalgebra::{DMatrix, Matrix3, Point2, Point3, Vector3};
use rand::Rng;

/// Number of samples of each P4Pf check.
pub const N_P4PF: usize = 5_000;

/// A P4Pf instance and its truth.
struct Instance {
    world: [Point3<f64>; 4],
    image: [Point2<f64>; 4],
    r: Matrix3<f64>,
    t: Vector3<f64>,
    f: f64,
}

/// The planarity ratio of four world points: `|det A|` over the product of `A`'s column norms.
fn planarity(world: &[Point3<f64>; 4]) -> f64 {
    let a = Matrix3::from_columns(&[1, 2, 3].map(|k| world[k].coords - world[0].coords));
    a.determinant().abs() / (a.column(0).norm() * a.column(1).norm() * a.column(2).norm())
}

fn instance(rng: &mut rand_pcg::Pcg64) -> Instance {
    loop {
        let f = st::log_uniform(rng, 300f64.log10(), 3000f64.log10());
        let r = st::rotation(rng);
        let t = Vector3::new(st::normal(rng), st::normal(rng), st::normal(rng));
        let mut world = [Point3::origin(); 4];
        let mut image = [Point2::origin(); 4];
        for i in 0..4 {
            let z = rng.random_range(2.0..10.0);
            let cam = Vector3::new(
                rng.random_range(-0.5..0.5) * z,
                rng.random_range(-0.4..0.4) * z,
                z,
            );
            world[i] = Point3::from(r.transpose() * (cam - t));
            image[i] = Point2::new(f * cam.x / cam.z, f * cam.y / cam.z);
        }
        if planarity(&world) >= 1e-2 {
            return Instance {
                world,
                image,
                r,
                t,
                f,
            };
        }
    }
}

/// The kernel inputs of an instance, formed as the solver forms them (image points scaled by
/// their mean distance from the principal point, `G = (A^T A)^-1` of the world's affine frame).
fn kernel_inputs(inst: &Instance) -> ([f64; 8], [f64; 6], [Vector3<f64>; 4], Matrix3<f64>) {
    let si = inst.image.iter().map(|p| p.coords.norm()).sum::<f64>() / 4.0;
    let m = inst.image.map(|p| Vector3::new(p.x / si, p.y / si, 1.0));
    let a = Matrix3::from_columns(&[1, 2, 3].map(|k| inst.world[k].coords - inst.world[0].coords));
    let ai = a.try_inverse().expect("non-coplanar");
    let g = ai * ai.transpose();
    let uv = [
        m[0].x, m[0].y, m[1].x, m[1].y, m[2].x, m[2].y, m[3].x, m[3].y,
    ];
    let gu = [
        g[(0, 0)],
        g[(0, 1)],
        g[(0, 2)],
        g[(1, 1)],
        g[(1, 2)],
        g[(2, 2)],
    ];
    (uv, gu, m, g)
}

/// A quadric `[xx, xy, yy, xz, yz, zz, x, y, z, 1]` at `v`, and the sum of its terms' absolute
/// values.
fn quadric_at(q: &[f64], v: &[f64; 3]) -> (f64, f64) {
    let [x, y, z] = *v;
    let terms = [x * x, x * y, y * y, x * z, y * z, z * z, x, y, z, 1.0];
    let value = terms.iter().zip(q).map(|(t, c)| t * c).sum();
    let scale = terms.iter().zip(q).map(|(t, c)| (t * c).abs()).sum();
    (value, scale)
}

/// Tolerance of the quadrics' comparison, relative to the absolute-value scale
/// `|a| |G| |b|^T`: both sides are short straight-line evaluations; 1e-12 leaves a factor above
/// 10^2 over their rounding.
const TOL_QUADRICS: f64 = 1e-12;

/// `p4pf_quadrics` at a random `(x, y, z)` against `<a, b>`, `<a, a> - <b, b>`, `<a, c>`,
/// `<b, c>` for the rows of `M_Y = [l_2 m_2 - m_1, l_3 m_3 - m_1, l_4 m_4 - m_1]`,
/// `l_k = 1 + (x, y, z)_k`, formed numerically.
#[must_use]
pub fn p4pf_quadrics(n: usize) -> Measurement {
    let seed = 501;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "p4pf_quadrics",
        "quadrics vs the Gram matrix M_Y G M_Y^T formed numerically",
        "|dq| / (|a| |G| |b|^T)",
        format!("{TOL_QUADRICS:e}"),
    );
    for i in 0..n {
        let inst = instance(&mut rng);
        let (uv, gu, m, g) = kernel_inputs(&inst);
        let v = [
            st::normal(&mut rng),
            st::normal(&mut rng),
            st::normal(&mut rng),
        ];
        let q = k::p4pf_quadrics(&uv, &gu);
        let my = Matrix3::from_columns(&[1, 2, 3].map(|c| m[c] * (1.0 + v[c - 1]) - m[0]));
        let gram = my * g * my.transpose();
        let abs = my.abs() * g.abs() * my.abs().transpose();
        let reference = [
            (gram[(0, 1)], abs[(0, 1)]),
            (gram[(0, 0)] - gram[(1, 1)], abs[(0, 0)] + abs[(1, 1)]),
            (gram[(0, 2)], abs[(0, 2)]),
            (gram[(1, 2)], abs[(1, 2)]),
        ];
        let mut worst = 0.0f64;
        for (j, (value, scale)) in reference.iter().enumerate() {
            let (kernel, _) = quadric_at(&q[10 * j..10 * j + 10], &v);
            worst = worst.max((kernel - value).abs() / scale);
        }
        t.record(worst, TOL_QUADRICS, || {
            format!("seed {seed} sample {i}: uv {uv:?}, g {gu:?}, at {v:?}")
        });
    }
    t.finish()
}

/// Three random quadrics through the point `p` (coefficients standard normal, the constant
/// term set so that they vanish at `p`).
fn planted(rng: &mut rand_pcg::Pcg64, p: &[f64; 3]) -> [[f64; 10]; 3] {
    let mut qs = [[0.0; 10]; 3];
    for q in &mut qs {
        for c in q.iter_mut() {
            *c = st::normal(rng);
        }
        q[9] = 0.0;
        q[9] = -quadric_at(q, p).0;
    }
    qs
}

/// The 21 inputs of `e3q3_octic` for three quadrics with `z` hidden (their `x^2, xy, y^2`
/// coefficients solved numerically, by nalgebra's LU), and the condition number of that 3 x 3
/// system (the inputs' rounding is `eps` times it, relative).
fn reduced(qs: &[[f64; 10]; 3]) -> Option<([f64; 21], f64)> {
    let c = Matrix3::from_fn(|i, j| qs[i][j]);
    let sv = c.singular_values();
    let cond = sv[0] / sv[2];
    let lu = c.lu();
    let mut m = [0.0; 21];
    // Columns of the right-hand sides: x, xz, y, yz, 1, z, zz.
    for (col, idx) in [6, 3, 7, 4, 9, 8, 5].into_iter().enumerate() {
        let rhs = Vector3::new(-qs[0][idx], -qs[1][idx], -qs[2][idx]);
        let sol = lu.solve(&rhs)?;
        for i in 0..3 {
            m[7 * i + col] = sol[i];
        }
    }
    cond.is_finite().then_some((m, cond))
}

/// A value and the absolute-value scale of its evaluation: sums and differences add the
/// scales, products multiply them.
#[derive(Clone, Copy)]
struct Scaled(f64, f64);

impl Scaled {
    fn add(self, o: Scaled) -> Scaled {
        Scaled(self.0 + o.0, self.1 + o.1)
    }
    fn sub(self, o: Scaled) -> Scaled {
        Scaled(self.0 - o.0, self.1 + o.1)
    }
    fn mul(self, o: Scaled) -> Scaled {
        Scaled(self.0 * o.0, self.1 * o.1)
    }
    fn neg(self) -> Scaled {
        Scaled(-self.0, self.1)
    }
}

/// `L(z)` evaluated numerically from the definitions (an independent evaluation of the
/// elimination the kernel expands symbolically): `A_i`, `B_i`, `C_i` at `z`, then
/// `L1 = x (xy) - y (x^2)`, `L2 = y (xy) - x (y^2)`, `L3 = y L1`, each with `x^2, xy, y^2`
/// replaced by their right-hand sides; with every entry's absolute-value scale.
fn l_numeric(m: &[f64; 21], z: f64) -> [[Scaled; 3]; 3] {
    let poly = |c: &[f64]| {
        let (mut v, mut a, mut pow) = (0.0, 0.0, 1.0);
        for ck in c {
            v += ck * pow;
            a += (ck * pow).abs();
            pow *= z;
        }
        Scaled(v, a)
    };
    let abc: [[Scaled; 3]; 3] = core::array::from_fn(|i| {
        let r = &m[7 * i..7 * i + 7];
        [poly(&r[0..2]), poly(&r[2..4]), poly(&r[4..7])]
    });
    let [[a1, b1, c1], [a2, b2, c2], [a3, b3, c3]] = abc;
    let zero = Scaled(0.0, 0.0);
    // cx2 x^2 + cxy xy + cy2 y^2 + cx x + cy y + k, the three monomials replaced.
    let reduce = |cx2: Scaled, cxy: Scaled, cy2: Scaled, cx: Scaled, cy: Scaled, k: Scaled| {
        [
            cx2.mul(a1).add(cxy.mul(a2)).add(cy2.mul(a3)).add(cx),
            cx2.mul(b1).add(cxy.mul(b2)).add(cy2.mul(b3)).add(cy),
            cx2.mul(c1).add(cxy.mul(c2)).add(cy2.mul(c3)).add(k),
        ]
    };
    let l1 = reduce(a2, b2.sub(a1), b1.neg(), c2, c1.neg(), zero);
    let l2 = reduce(a3.neg(), a2.sub(b3), b2, c3.neg(), c2, zero);
    let l3 = reduce(zero, l1[0], l1[1], zero, l1[2], zero);
    [l1, l2, l3]
}

/// `L(z)` from the kernel's output.
fn l_at(out: &[f64; 42], z: f64) -> Matrix3<f64> {
    let lens = [3, 3, 4, 3, 3, 4, 4, 4, 5];
    let mut at = 9;
    let mut l = Matrix3::zeros();
    for (n, len) in lens.into_iter().enumerate() {
        l[(n / 3, n % 3)] = out[at..at + len]
            .iter()
            .rev()
            .fold(0.0, |acc, c| acc * z + c);
        at += len;
    }
    l
}

/// The octic at `z` and the sum of its terms' absolute values.
fn octic_at(d: &[f64], z: f64) -> (f64, f64) {
    let mut pow = 1.0;
    let (mut value, mut scale) = (0.0, 0.0);
    for c in d {
        value += c * pow;
        scale += (c * pow).abs();
        pow *= z;
    }
    (value, scale)
}

/// Tolerance of the octic against `det L(z)` of the numerically evaluated `L`, relative to
/// the permanent of the absolute-value scales of `L`'s entries (every term of the determinant's
/// expansion, each evaluated with absolute values): both sides are straight-line evaluations of
/// depth below 64, `gamma_64` about 7e-15 of that scale; 1e-12 leaves a factor above 10^2.
const TOL_E3Q3_DET: f64 = 1e-12;

/// `det` of the values of `l` (cofactor expansion), and the permanent of its scales.
fn det_scaled(l: &[[Scaled; 3]; 3]) -> (f64, f64) {
    let v = Matrix3::from_fn(|r, c| l[r][c].0);
    let a = DMatrix::from_fn(3, 3, |r, c| l[r][c].1);
    (v.determinant(), crate::reference::permanent(&a))
}

/// `e3q3_octic`: the octic at a random `z` against `det L(z)` with `L` evaluated numerically
/// from the definitions, on three random quadrics.
#[must_use]
pub fn e3q3_determinant(n: usize) -> Measurement {
    let seed = 502;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "e3q3_octic",
        "octic vs det L(z), L evaluated numerically, at a random z",
        "|dD| / permanent(|L| scales)",
        format!("{TOL_E3Q3_DET:e}"),
    );
    for i in 0..n {
        let p = [
            st::normal(&mut rng),
            st::normal(&mut rng),
            st::normal(&mut rng),
        ];
        let qs = planted(&mut rng, &p);
        let Some((m, _)) = reduced(&qs) else {
            continue;
        };
        let out = k::e3q3_octic(&m);
        let z = st::normal(&mut rng);
        let (reference, scale) = det_scaled(&l_numeric(&m, z));
        let (kernel, _) = octic_at(&out[0..9], z);
        t.record((kernel - reference).abs() / scale, TOL_E3Q3_DET, || {
            format!("seed {seed} sample {i}: m {m:?}, z {z:e}")
        });
    }
    t.finish()
}

/// Tolerance of the planted solution: the octic at its `z` relative to the permanent of `L`'s
/// scales, and `L(z) (x, y, 1)` relative to its scale, both over the condition number of the
/// 3 x 3 solve that forms the inputs (which rounds them by `eps` times it); 1e-12 leaves a
/// factor above 10^2 over `gamma_64`.
const TOL_E3Q3_ROOT: f64 = 1e-12;

/// A planted solution `(x, y, z)` of three random quadrics: `z` a root of the octic, `(x, y, 1)`
/// a null vector of `L(z)` (the kernel's `L` and the numeric one).
#[must_use]
pub fn e3q3_known_root(n: usize) -> Measurement {
    let seed = 503;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "e3q3_octic",
        "planted solution: octic root, null vector of L",
        "max(|D(z*)|, |L(z*) v|) / scale / cond(C)",
        format!("{TOL_E3Q3_ROOT:e}"),
    );
    for i in 0..n {
        let p = [
            st::normal(&mut rng),
            st::normal(&mut rng),
            st::normal(&mut rng),
        ];
        let qs = planted(&mut rng, &p);
        let Some((m, cond)) = reduced(&qs) else {
            continue;
        };
        let out = k::e3q3_octic(&m);
        let ln = l_numeric(&m, p[2]);
        let (_, scale) = det_scaled(&ln);
        let (value, _) = octic_at(&out[0..9], p[2]);
        let l = l_at(&out, p[2]);
        let v = Vector3::new(p[0], p[1], 1.0);
        let lscale = Matrix3::from_fn(|r, c| ln[r][c].1) * v.abs();
        let null = ((l * v).abs().component_div(&lscale)).max();
        let err = (value.abs() / scale).max(null) / cond;
        t.record(err, TOL_E3Q3_ROOT, || {
            format!("seed {seed} sample {i}: planted {p:?}, cond {cond:e}")
        });
    }
    t.finish()
}

/// The three-quadric solver [`e3q3`], with each of its root finders (the derivative sequence
/// and the Sturm sequence): every solution solves the three quadrics to 1e-10 (each residual
/// relative to its terms), the planted one is among them (1e-8), and their number equals the
/// number of real roots of the octic with `z` hidden (the companion matrix's eigenvalues:
/// another root finder, and possibly another hidden variable than the solver's),
/// on every instance whose roots are not within 1e-5 of the real axis' boundary (counted in
/// the report, not compared).
#[must_use]
pub fn e3q3_solutions(n: usize) -> Measurement {
    let seed = 504;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "e3q3_octic",
        "solver: solutions solve the quadrics, the planted one found, as many as the companion matrix's real roots",
        "max residual / terms; count mismatch = inf",
        "1e-10".into(),
    );
    let mut ambiguous = 0usize;
    for i in 0..n {
        let p = [
            st::normal(&mut rng),
            st::normal(&mut rng),
            st::normal(&mut rng),
        ];
        let qs = planted(&mut rng, &p);
        // Both root finders: the derivative sequence (every root) and the Sturm sequence
        // (roots above a finite value, -1e6 here: below these instances' roots, or the count
        // differs).
        let all = e3q3(&qs, f64::NEG_INFINITY, 0.0);
        let sturm = e3q3(&qs, -1e6, 0.0);
        let mut worst = 0.0f64;
        let mut found = true;
        for sols in [&all, &sturm] {
            for s in sols {
                for q in &qs {
                    let (v, scale) = quadric_at(q, s);
                    worst = worst.max(v.abs() / scale);
                }
            }
            found &= sols
                .iter()
                .any(|s| (0..3).all(|j| (s[j] - p[j]).abs() <= 1e-8 * (1.0 + p[j].abs())));
        }
        if !found {
            worst = f64::INFINITY;
        }
        let Some((m, _)) = reduced(&qs) else {
            ambiguous += 1;
            continue;
        };
        let out = k::e3q3_octic(&m);
        let (roots, closest_complex) = companion_roots(&out[0..9]);
        if closest_complex < 1e-5 {
            ambiguous += 1;
        } else if roots.len() != all.len() || roots.len() != sturm.len() {
            worst = f64::INFINITY;
        }
        t.record(worst, 1e-10, || {
            format!(
                "seed {seed} sample {i}: {} / {} solutions (derivative / Sturm sequence), \
                 companion count {}, found {found}",
                all.len(),
                sturm.len(),
                roots.len()
            )
        });
    }
    let mut m = t.finish();
    if ambiguous > 0 {
        m.worst_input = format!(
            "{} ({ambiguous} near-boundary instances not counted)",
            m.worst_input
        );
    }
    m
}

/// The P4Pf solver: the true pose and focal length among the solutions (rotation to 1e-7
/// degrees, focal length to 1e-9 relative, translation to 1e-8 relative), on instances at
/// least 1 % out of coplanarity; the measurement is the true solution's largest relative
/// error (infinite when it is missing).
#[must_use]
pub fn p4pf_solutions(n: usize) -> Measurement {
    let seed = 505;
    let mut rng = st::rng(seed);
    let mut t = Tracker::new(
        "p4pf_quadrics",
        "solver: the true pose and focal length among the solutions",
        "max(rotation deg / 1e2, |df| / f, |dt| / (1 + |t|)) of the closest",
        "1e-9".into(),
    );
    for i in 0..n {
        let inst = instance(&mut rng);
        let sols = p4pf(&inst.world, &inst.image);
        let err = sols
            .iter()
            .map(|s| {
                (rotation_error_deg(&s.rotation, &inst.r) / 1e2)
                    .max((s.focal / inst.f - 1.0).abs())
                    .max((s.translation - inst.t).norm() / (1.0 + inst.t.norm()))
            })
            .fold(f64::INFINITY, f64::min);
        t.record(err, 1e-9, || {
            format!(
                "seed {seed} sample {i}: {} solutions, f {}, planarity {:e}",
                sols.len(),
                inst.f,
                planarity(&inst.world)
            )
        });
    }
    t.finish()
}
