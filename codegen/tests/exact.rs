//! Exact (rational) self-checks of the symbolic definitions and of the structured programs.
//!
//! The numeric checks of the *emitted* code live in the independent `eopnp-verify` crate; these
//! tests pin the algebra itself: the cost table of docs/algorithm.md (G1), the equivalence of the
//! structured (Bezout, cofactor) evaluations with the expanded definitions and with the 6x6
//! Sylvester determinant, and exact vanishing at known common roots.

use eopnp_codegen::defs::{cost, resultant};
use eopnp_codegen::poly::{det_bareiss, q, Poly, Var, Q};
use eopnp_codegen::program::Kernel;
use eopnp_codegen::{render_all, KERNELS};
use std::collections::BTreeMap;

/// Deterministic small rationals (a linear congruential sequence; no floating point).
struct Lcg(u64);
impl Lcg {
    fn next_q(&mut self) -> Q {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let num = ((self.0 >> 33) % 19) as i128 - 9;
        let den = ((self.0 >> 20) % 5) as i128 + 1;
        Q::new(num, den)
    }
}

fn kernel(name: &str) -> Kernel {
    KERNELS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, f)| f())
        .unwrap_or_else(|| panic!("no kernel {name}"))
}

#[test]
fn rendering_is_deterministic() {
    // Two renderings of the whole manifest are byte-identical (BTreeMap order everywhere).
    assert_eq!(render_all(), render_all());
}

#[test]
fn cost_table_matches_algorithm_md() {
    // codegen/tests/data/cost_coeff_table.txt is the G1 table of docs/algorithm.md, written
    // independently by sympy during development. Parse "c[ k] ... = +1*M00 -2*M04 ..." lines.
    let text = include_str!("data/cost_coeff_table.txt");
    let k = cost::cost_coefficients(false);
    let names = &k.ring.names;
    let mut seen = 0;
    for line in text.lines().filter(|l| l.starts_with("c[")) {
        let idx: usize = line[2..line.find(']').unwrap()].trim().parse().unwrap();
        let rhs = line.split('=').nth(1).unwrap();
        let mut expected: BTreeMap<String, i128> = BTreeMap::new();
        for tok in rhs.split_whitespace() {
            let (coef, m) = tok.split_once("*M").unwrap();
            expected.insert(format!("m{m}"), coef.parse().unwrap());
        }
        let got: BTreeMap<String, i128> = k.outputs[idx]
            .1
            .terms
            .iter()
            .map(|(mono, c)| {
                assert_eq!(mono.0.len(), 1);
                assert!(c.is_integer());
                (names[mono.0[0].0 as usize].clone(), *c.numer())
            })
            .collect();
        assert_eq!(got, expected, "coefficient c[{idx}]");
        seen += 1;
    }
    assert_eq!(seen, 35);
    let terms: usize = k.outputs.iter().map(|(_, p)| p.len()).sum();
    assert_eq!(terms, 264, "G1 has 264 (monomial, entry) terms");
}

#[test]
fn planar_cost_has_124_terms_and_35_coefficients() {
    let k = cost::cost_coefficients(true);
    let terms: usize = k.outputs.iter().map(|(_, p)| p.len()).sum();
    assert_eq!(terms, 124);
    assert!(k.outputs.iter().all(|(_, p)| !p.is_zero()));
}

/// Evaluates a kernel's structured program and its expansion at the same rational point.
fn structured_equals_expanded(name: &str, seed: u64) {
    let k = kernel(name);
    let expanded = k.expanded_outputs();
    let mut rng = Lcg(seed);
    let mut point: BTreeMap<Var, Q> = BTreeMap::new();
    for i in &k.inputs {
        for &v in &i.vars {
            point.insert(v, rng.next_q());
        }
    }
    let a = k.eval_structured(&|v| point[&v]);
    let b: Vec<Q> = expanded.iter().map(|p| p.eval(&|v| point[&v])).collect();
    assert_eq!(
        a, b,
        "{name}: structured program differs from its expansion"
    );
}

#[test]
fn structured_programs_equal_their_expansions() {
    for (name, _) in KERNELS {
        structured_equals_expanded(name, 7);
    }
}

/// The gradient cubics of case 2 as printed in docs/algorithm.md, `nullspace` case 2.
fn case2_spec_gradients(qv: &[Poly], p: &[Poly], x: &Poly, y: &Poly) -> (Poly, Poly) {
    let (q00, q01, q02, q11, q12, q22) = (&qv[0], &qv[1], &qv[2], &qv[3], &qv[4], &qv[5]);
    let g1 = q00
        .mul(&x.pow(3))
        .scale(&q(4))
        .add(&q01.mul(y).mul(&x.pow(2)).scale(&q(6)))
        .add(
            &q11.add(&q02.scale(&q(2)))
                .mul(&y.pow(2))
                .scale(&q(2))
                .sub(&p[0].scale(&q(4)))
                .mul(x),
        )
        .add(&q12.mul(&y.pow(3)).scale(&q(2)))
        .sub(&p[1].mul(y).scale(&q(2)));
    let g2 = q01
        .mul(&x.pow(3))
        .scale(&q(2))
        .add(
            &q11.add(&q02.scale(&q(2)))
                .mul(y)
                .mul(&x.pow(2))
                .scale(&q(2)),
        )
        .add(
            &q12.mul(&y.pow(2))
                .scale(&q(6))
                .sub(&p[1].scale(&q(2)))
                .mul(x),
        )
        .add(&q22.mul(&y.pow(3)).scale(&q(4)))
        .sub(&p[2].mul(y).scale(&q(4)));
    (g1, g2)
}

#[test]
fn case2_cubics_match_the_printed_gradient() {
    let k = kernel("case2_cubics");
    let qv: Vec<Poly> = k.inputs[0].vars.iter().map(|&v| Poly::var(v)).collect();
    let pv: Vec<Poly> = k.inputs[1].vars.iter().map(|&v| Poly::var(v)).collect();
    let y = Poly::var(k.inputs[2].vars[0]);
    // x is internal to the kernel: rebuild the cubics from the outputs with a fresh symbol.
    let x = Poly::var(9999);
    let (g1, g2) = case2_spec_gradients(&qv, &pv, &x, &y);
    let from_kernel = |off: usize| {
        (0..4).fold(Poly::zero(), |acc, n| {
            acc.add(&k.outputs[off + n].1.mul(&x.pow(n as u32)))
        })
    };
    assert_eq!(from_kernel(0), g1);
    assert_eq!(from_kernel(4), g2);
}

/// Substitutes a rational point for every input of `k`, keeping the internal hidden variable.
fn sylvester_at_point(cubics: &Kernel, seed: u64) -> (Vec<Q>, BTreeMap<Var, Q>) {
    // cubics outputs are the two cubics in x at the scalar input y (last input).
    let mut rng = Lcg(seed);
    let mut point: BTreeMap<Var, Q> = BTreeMap::new();
    let y = cubics.inputs.last().unwrap().vars[0];
    for i in &cubics.inputs[..cubics.inputs.len() - 1] {
        for &v in &i.vars {
            point.insert(v, rng.next_q());
        }
    }
    let sub = |p: &Poly| p.substitute_all(&|v| point.get(&v).map(|c| Poly::constant(*c)));
    let g1: [Poly; 4] = std::array::from_fn(|n| sub(&cubics.outputs[n].1));
    let g2: [Poly; 4] = std::array::from_fn(|n| sub(&cubics.outputs[4 + n].1));
    let det = resultant::sylvester_resultant(&g1, &g2);
    let coeffs: Vec<Q> = det
        .collect(y)
        .iter()
        .map(|c| c.as_constant().expect("univariate after substitution"))
        .collect();
    (coeffs, point)
}

#[test]
fn resultants_equal_the_sylvester_determinant() {
    for (case, res_name, cub_name) in [
        (2, "case2_resultant", "case2_cubics"),
        (3, "case3_resultant", "case3_cubics"),
    ] {
        let res = kernel(res_name);
        let cub = kernel(cub_name);
        for seed in 1..6 {
            let (syl, point) = sylvester_at_point(&cub, seed);
            // Map the cubics kernel's input symbols to the resultant kernel's (same names).
            let by_name: BTreeMap<&str, Q> = point
                .iter()
                .map(|(v, c)| (cub.ring.names[*v as usize].as_str(), *c))
                .collect();
            let out = res.eval_structured(&|v| by_name[res.ring.names[v as usize].as_str()]);
            let coeff = |j: usize| syl.get(j).copied().unwrap_or_default();
            if case == 2 {
                for (i, j) in [1usize, 3, 5, 7, 9].iter().enumerate() {
                    assert_eq!(out[i], coeff(*j), "case 2 seed {seed} y^{j}");
                }
                for j in [0usize, 2, 4, 6, 8] {
                    assert_eq!(coeff(j), Q::default(), "case 2 resultant is odd");
                }
            } else {
                assert!(syl.len() <= 10);
                for (j, o) in out.iter().enumerate() {
                    assert_eq!(*o, coeff(j), "case 3 seed {seed} y^{j}");
                }
            }
        }
    }
}

#[test]
fn case3_resultant_has_full_degree_9() {
    let k = kernel("case3_resultant");
    let expanded = k.expanded_outputs();
    assert_eq!(expanded.len(), 10);
    assert!(!expanded[9].is_zero());
    let terms: usize = expanded.iter().map(Poly::len).sum();
    assert_eq!(terms, 1164, "docs/algorithm.md G5");
}

/// Exact inverse of a 3x3 rational matrix (None if singular).
fn inv3(a: &[[Q; 3]; 3]) -> Option<[[Q; 3]; 3]> {
    let m = |r: usize, c: usize| a[r][c];
    let cof = |r: usize, c: usize| {
        let rs: Vec<usize> = (0..3).filter(|&i| i != r).collect();
        let cs: Vec<usize> = (0..3).filter(|&i| i != c).collect();
        let d = m(rs[0], cs[0]) * m(rs[1], cs[1]) - m(rs[0], cs[1]) * m(rs[1], cs[0]);
        if (r + c) % 2 == 0 {
            d
        } else {
            -d
        }
    };
    let det = m(0, 0) * cof(0, 0) + m(0, 1) * cof(0, 1) + m(0, 2) * cof(0, 2);
    if det == Q::default() {
        return None;
    }
    Some(std::array::from_fn(|i| {
        std::array::from_fn(|j| cof(j, i) / det)
    }))
}

#[test]
#[allow(clippy::needless_range_loop)] // symmetric fill f[i][j] = f[j][i]
fn case4_determinant_vanishes_at_a_known_root() {
    // Three quadrics in (1, k1, k2, k3) with a common root (k1*, k2*, k3*): random symmetric
    // 4x4 forms, each with F00 adjusted so that w^T F w = 0 at w = (1, k1*, k2*, k3*).
    let det_k = kernel("case4_determinant");
    let mat_k = kernel("case4_matrix");
    let names = resultant::case4_input_names();
    for seed in 1..4u64 {
        let mut rng = Lcg(seed * 101);
        let w = [q(1), rng.next_q(), rng.next_q(), rng.next_q()];
        let mut forms = Vec::new();
        for _ in 0..3 {
            let mut f = [[Q::default(); 4]; 4];
            for i in 0..4 {
                for j in i..4 {
                    let x = rng.next_q();
                    f[i][j] = x;
                    f[j][i] = x;
                }
            }
            let mut val = Q::default();
            for i in 0..4 {
                for j in 0..4 {
                    val += w[i] * f[i][j] * w[j];
                }
            }
            f[0][0] -= val; // w0 = 1
            forms.push(f);
        }
        // Mm (constant) and N(k1) columns [deg 1, deg 1, deg 2] per docs/algorithm.md, `nullspace`
        // case 4.
        let mm: [[Q; 3]; 3] =
            std::array::from_fn(|e| [forms[e][2][2], forms[e][3][3], q(2) * forms[e][2][3]]);
        let Some(inv) = inv3(&mm) else { continue };
        // n[e][j][n]: coefficient of k1^n in N_ej
        let n: Vec<[[Q; 3]; 3]> = forms
            .iter()
            .map(|f| {
                [
                    [q(2) * f[0][2], q(2) * f[1][2], Q::default()],
                    [q(2) * f[0][3], q(2) * f[1][3], Q::default()],
                    [f[0][0], q(2) * f[0][1], f[1][1]],
                ]
            })
            .collect();
        // T = -Mm^-1 N
        let t = |i: usize, j: usize, p: usize| -> Q {
            -(0..3).map(|l| inv[i][l] * n[l][j][p]).sum::<Q>()
        };
        let by_name: BTreeMap<String, Q> = names
            .iter()
            .map(|(i, j, p, name)| (name.clone(), t(*i, *j, *p)))
            .collect();
        let d = det_k.eval_structured(&|v| by_name[&det_k.ring.names[v as usize]]);
        let value: Q = d
            .iter()
            .enumerate()
            .map(|(p, c)| {
                let mut x = *c;
                for _ in 0..p {
                    x *= w[1];
                }
                x
            })
            .sum();
        assert_eq!(
            value,
            Q::default(),
            "det M(k1*) must vanish exactly (seed {seed})"
        );
        // And M(k1*) [k2*, k3*, 1] = 0.
        let m = mat_k.eval_structured(&|v| by_name[&mat_k.ring.names[v as usize]]);
        let entry = |i: usize, j: usize| -> Q {
            (0..5)
                .map(|p| {
                    let mut x = m[(3 * i + j) * 5 + p];
                    for _ in 0..p {
                        x *= w[1];
                    }
                    x
                })
                .sum()
        };
        let yv = [w[2], w[3], q(1)];
        for i in 0..3 {
            let r: Q = (0..3).map(|j| entry(i, j) * yv[j]).sum();
            assert_eq!(r, Q::default(), "row {i} of M(k1*) y* (seed {seed})");
        }
    }
}

#[test]
fn case4_determinant_has_degree_8_and_17395_terms() {
    let k = kernel("case4_determinant");
    let expanded = k.expanded_outputs();
    assert!(!expanded[8].is_zero());
    let terms: usize = expanded.iter().map(Poly::len).sum();
    assert_eq!(terms, 17395, "docs/algorithm.md G6");
}

#[test]
fn bareiss_agrees_with_cofactor_on_a_symbolic_sylvester() {
    // Small symbolic case: two quadratics' 4x4 Sylvester matrix via Bareiss equals the textbook
    // resultant a2^2 c0^2 - ... checked by vanishing at a common root.
    let a: Vec<Poly> = (0..3).map(Poly::var).collect();
    let r = q(3);
    // second quadratic (x - r)(x - 2) and first a0 + a1 x + a2 x^2 with a0 = -(a1 r + a2 r^2)
    let a0 = a[1].scale(&r).add(&a[2].scale(&(r * r))).neg();
    let b = [q(6), q(-5), q(1)].map(Poly::constant);
    let rows = vec![
        vec![a[2].clone(), a[1].clone(), a0.clone(), Poly::zero()],
        vec![Poly::zero(), a[2].clone(), a[1].clone(), a0],
        vec![b[2].clone(), b[1].clone(), b[0].clone(), Poly::zero()],
        vec![Poly::zero(), b[2].clone(), b[1].clone(), b[0].clone()],
    ];
    assert!(
        det_bareiss(&rows).is_zero(),
        "common root x = 3 makes the resultant vanish"
    );
}

/// `up2p_quadratic` vanishes exactly at the true rotation: a rational instance (rational
/// `s = tan(theta / 2)`, rational world points, centres and translation; the constraint rows
/// need not be unit vectors, only orthogonal to the rays, so `v x e_x` and `v x (v x e_x)` are
/// rational), for one camera and for a rig.
#[test]
fn up2p_quadratic_vanishes_at_the_true_rotation() {
    let k = kernel("up2p_quadratic");
    let mut rng = Lcg(11);
    let cross = |a: &[Q; 3], b: &[Q; 3]| -> [Q; 3] {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    for trial in 0..20 {
        let s = rng.next_q();
        let one = Q::from_integer(1);
        let (cm, cp) = (one - s * s, one + s * s);
        let two_s = Q::from_integer(2) * s;
        // R_y (scaled by 1 / (1 + s^2)) applied to x.
        let rot = |x: &[Q; 3]| -> [Q; 3] {
            [
                (cm * x[0] + two_s * x[2]) / cp,
                x[1],
                (cm * x[2] - two_s * x[0]) / cp,
            ]
        };
        let t = [rng.next_q(), rng.next_q(), rng.next_q()];
        let mut rows: Vec<[Q; 3]> = Vec::new();
        let mut p: Vec<Q> = Vec::new();
        let mut e: Vec<Q> = Vec::new();
        for _ in 0..2 {
            let x = [rng.next_q(), rng.next_q(), rng.next_q()];
            let c = if trial % 2 == 0 {
                [Q::from_integer(0); 3]
            } else {
                [rng.next_q(), rng.next_q(), rng.next_q()]
            };
            let rx = rot(&x);
            let v = [
                rx[0] + t[0] - c[0],
                rx[1] + t[1] - c[1],
                rx[2] + t[2] - c[2],
            ];
            let a0 = cross(&v, &[one, Q::from_integer(0), Q::from_integer(0)]);
            let a0 = if a0.iter().all(|z| *z == Q::from_integer(0)) {
                cross(&v, &[Q::from_integer(0), one, Q::from_integer(0)])
            } else {
                a0
            };
            let a1 = cross(&v, &a0);
            for a in [a0, a1] {
                e.push(a[0] * c[0] + a[1] * c[1] + a[2] * c[2]);
                rows.push(a);
            }
            p.extend(x);
        }
        let a: Vec<Q> = rows.iter().flat_map(|r| r.iter().copied()).collect();
        let mut point: BTreeMap<Var, Q> = BTreeMap::new();
        let values: Vec<Q> = a.into_iter().chain(p).chain(e).collect();
        let vars: Vec<Var> = k
            .inputs
            .iter()
            .flat_map(|i| i.vars.iter().copied())
            .collect();
        assert_eq!(vars.len(), values.len());
        for (v, x) in vars.into_iter().zip(values) {
            point.insert(v, x);
        }
        let c = k.eval_structured(&|v| point[&v]);
        let at_s = c[0] + c[1] * s + c[2] * s * s;
        assert_eq!(at_s, Q::from_integer(0), "trial {trial}: q(s*) = {at_s}");
        assert!(
            c.iter().any(|z| *z != Q::from_integer(0)),
            "trial {trial}: all coefficients zero"
        );
    }
}

/// `e3q3_octic` vanishes exactly at a planted solution: rational relations `x^2 = A1 x + B1 y +
/// C1`, `xy = ...`, `y^2 = ...` (random rational `A_i`, `B_i` and the `z`, `z^2` coefficients
/// of `C_i`, the constant terms set so that each holds at a rational `(x*, y*, z*)`): the octic
/// is 0 at `z*` and `(x*, y*, 1)` is a null vector of `L(z*)`.
#[test]
fn e3q3_octic_vanishes_at_a_planted_solution() {
    let k = kernel("e3q3_octic");
    let mut rng = Lcg(17);
    let zero = Q::from_integer(0);
    for trial in 0..10 {
        let (x, y, z) = (rng.next_q(), rng.next_q(), rng.next_q());
        let mut m: Vec<Q> = Vec::new();
        for lhs in [x * x, x * y, y * y] {
            let r: Vec<Q> = (0..7).map(|_| rng.next_q()).collect();
            let rhs_rest = (r[0] + r[1] * z) * x + (r[2] + r[3] * z) * y + r[5] * z + r[6] * z * z;
            let mut r = r;
            r[4] = lhs - rhs_rest;
            m.extend(r);
        }
        let vars: Vec<Var> = k
            .inputs
            .iter()
            .flat_map(|i| i.vars.iter().copied())
            .collect();
        let point: BTreeMap<Var, Q> = vars.into_iter().zip(m).collect();
        let out = k.eval_structured(&|v| point[&v]);
        let horner = |c: &[Q]| c.iter().rev().fold(zero, |acc, ci| acc * z + *ci);
        assert_eq!(horner(&out[0..9]), zero, "trial {trial}: octic(z*)");
        assert!(
            out[0..9].iter().any(|c| *c != zero),
            "trial {trial}: octic is 0"
        );
        let lens = [3, 3, 4, 3, 3, 4, 4, 4, 5];
        let mut at = 9;
        let mut l = [zero; 9];
        for (n, len) in lens.into_iter().enumerate() {
            l[n] = horner(&out[at..at + len]);
            at += len;
        }
        for r in 0..3 {
            let v = l[3 * r] * x + l[3 * r + 1] * y + l[3 * r + 2];
            assert_eq!(v, zero, "trial {trial}: row {r} of L(z*) (x*, y*, 1)");
        }
    }
}

/// `p4pf_quadrics` vanish exactly at the true depth ratios of a rational camera: a rational
/// rotation (Cayley, rational parameters), translation, focal length and world points, so the
/// image points, `G = (A^T A)^-1` and the ratios `l_i = z_i / z_1` are rational; each quadric is
/// 0 at `(l_2 - 1, l_3 - 1, l_4 - 1)`.
#[test]
fn p4pf_quadrics_vanish_at_the_true_depth_ratios() {
    let k = kernel("p4pf_quadrics");
    let mut rng = Lcg(23);
    let zero = Q::from_integer(0);
    let one = Q::from_integer(1);
    let mut checked = 0;
    // Small integers (the rationals of the instance stay within i128).
    let int = |rng: &mut Lcg| Q::from_integer(*rng.next_q().numer() % 3);
    for _ in 0..40 {
        let s = [int(&mut rng), int(&mut rng), int(&mut rng)];
        let n2 = one + s[0] * s[0] + s[1] * s[1] + s[2] * s[2];
        // Cayley: R = ((1 - s.s) I + 2 s s^T + 2 [s]x) / (1 + s.s).
        let d = one - (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
        let two = Q::from_integer(2);
        let r: [[Q; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                let diag = if i == j { d } else { zero };
                let cross = match (i, j) {
                    (0, 1) => -s[2],
                    (0, 2) => s[1],
                    (1, 0) => s[2],
                    (1, 2) => -s[0],
                    (2, 0) => -s[1],
                    (2, 1) => s[0],
                    _ => zero,
                };
                (diag + two * s[i] * s[j] + two * cross) / n2
            })
        });
        let t = [int(&mut rng), int(&mut rng), Q::from_integer(20)];
        let f = Q::from_integer(7);
        let world: Vec<[Q; 3]> = (0..4)
            .map(|_| [int(&mut rng), int(&mut rng), int(&mut rng)])
            .collect();
        let cam: Vec<[Q; 3]> = world
            .iter()
            .map(|x| {
                std::array::from_fn(|i| r[i][0] * x[0] + r[i][1] * x[1] + r[i][2] * x[2] + t[i])
            })
            .collect();
        if cam.iter().any(|c| c[2] == zero) {
            continue;
        }
        let a: [[Q; 3]; 3] =
            std::array::from_fn(|i| std::array::from_fn(|j| world[j + 1][i] - world[0][i]));
        let ata: [[Q; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).fold(zero, |acc, kk| acc + a[kk][i] * a[kk][j]))
        });
        let Some(g) = inv3(&ata) else {
            continue;
        };
        let mut values: Vec<Q> = Vec::new();
        for c in &cam {
            values.push(f * c[0] / c[2]);
            values.push(f * c[1] / c[2]);
        }
        values.extend([g[0][0], g[0][1], g[0][2], g[1][1], g[1][2], g[2][2]]);
        let vars: Vec<Var> = k
            .inputs
            .iter()
            .flat_map(|i| i.vars.iter().copied())
            .collect();
        let point: BTreeMap<Var, Q> = vars.into_iter().zip(values).collect();
        let out = k.eval_structured(&|v| point[&v]);
        let mu = [1, 2, 3].map(|i| cam[i][2] / cam[0][2] - one);
        let terms = |x: Q, y: Q, z: Q| [x * x, x * y, y * y, x * z, y * z, z * z, x, y, z, one];
        for n in 0..4 {
            let v = terms(mu[0], mu[1], mu[2])
                .iter()
                .zip(&out[10 * n..10 * n + 10])
                .fold(zero, |acc, (t, c)| acc + *t * *c);
            assert_eq!(v, zero, "quadric {n} at the true ratios");
        }
        checked += 1;
    }
    assert!(checked >= 20, "{checked} instances");
}
