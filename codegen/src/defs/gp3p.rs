//! The generalized three-point pose (gP3P; docs/algorithm.md, G8 "The generalized minimal solver"):
//! three rays `c_i + lambda_i v_i` (centre and unit direction in the rig frame) through three
//! world points `X_i`. The rigid motion preserves distances, so the depths `lambda_i` solve the
//! three quadrics
//!
//! `E_ij = |c_i + l_i v_i - c_j - l_j v_j|^2 - |X_i - X_j|^2`
//! `     = l_i^2 + l_j^2 - 2 a_ij l_i l_j + 2 b_ij l_i + 2 c_ij l_j + d_ij = 0`
//!
//! with `a_ij = v_i . v_j`, `b_ij = v_i . (c_i - c_j)`, `c_ij = v_j . (c_j - c_i)` and
//! `d_ij = |c_i - c_j|^2 - |X_i - X_j|^2` (Bezout: at most 8 solutions). The elimination:
//!
//! 1. `E13` and `E23` are monic quadratics in `l3`, `l3^2 + p_k l3 + q_k`; their resultant in
//!    `l3` is `R(l1, l2) = (q1 - q2)^2 + (p1 - p2)(p1 q2 - p2 q1)`, of total degree 4, and where
//!    `p1 != p2` the common root is `l3 = (q2 - q1) / (p1 - p2)`.
//! 2. `E12` is a monic quadratic in `l2`, `l2^2 + P l2 + Q`: `R` reduced modulo it is linear in
//!    `l2`, `r1(l1) l2 + r0(l1)` (`deg r1 <= 3`, `deg r0 <= 4`), and where `r1 != 0` the common
//!    root is `l2 = -r0 / r1`.
//! 3. The resultant of `E12` and `r1 l2 + r0` in `l2` is the octic
//!    `F(l1) = r0^2 - P r0 r1 + Q r1^2`, whose real roots are the candidate `l1`.
//!
//! For one centre (`c_i` equal) the system is Grunert's P3P and `F` is even in `l1`.

use crate::poly::{q, Poly, Var};
use crate::program::{Kernel, UPoly};

const DEF: &str = "codegen/src/defs/gp3p.rs";

/// The input names of the three pairs' coefficients, `[a12, b12, c12, d12, a13, ..., d23]`.
pub fn input_names() -> Vec<String> {
    let mut names = Vec::new();
    for pair in ["12", "13", "23"] {
        for c in ["a", "b", "c", "d"] {
            names.push(format!("{c}{pair}"));
        }
    }
    names
}

/// `E_ij` as a polynomial in `(li, lj)` from its coefficients `[a, b, c, d]`.
fn quadric(e: &[Poly], li: &Poly, lj: &Poly) -> Poly {
    let (a, b, c, d) = (&e[0], &e[1], &e[2], &e[3]);
    li.mul(li)
        .add(&lj.mul(lj))
        .sub(&a.mul(li).mul(lj).scale(&q(2)))
        .add(&b.mul(li).scale(&q(2)))
        .add(&c.mul(lj).scale(&q(2)))
        .add(d)
}

/// `p` reduced modulo the monic quadratic `y^2 + pp y + qq` in `y` (coefficients polynomials
/// in the other variables): the remainder `[r0, r1]`, `p = r1 y + r0 (mod ...)`.
fn reduce_mod_monic_quadratic(p: &UPoly, pp: &Poly, qq: &Poly) -> [Poly; 2] {
    // Highest power first: y^k = y^(k-2) (-pp y - qq).
    let mut c: Vec<Poly> = p.0.clone();
    while c.len() > 2 {
        let top = c.pop().expect("non-empty");
        let k = c.len(); // the popped power is y^k
        c[k - 1] = c[k - 1].sub(&top.mul(pp));
        c[k - 2] = c[k - 2].sub(&top.mul(qq));
    }
    c.resize(2, Poly::zero());
    [c[0].clone(), c[1].clone()]
}

/// The elimination of gP3P: the octic `F(l1)` and the back-substitution polynomials `r1`, `r0`.
pub fn gp3p_elimination() -> Kernel {
    let mut k = Kernel::new("gp3p_elimination", DEF);
    k.doc(
        "The generalized three-point pose (docs/algorithm.md, G8): \
         from the coefficients of the three distance quadrics `E_ij = l_i^2 + l_j^2 - 2 a_ij l_i \
         l_j + 2 b_ij l_i + 2 c_ij l_j + d_ij` in the depths along the rays, the octic `F(l1)` \
         whose real roots are the first depths, and the polynomials `r1(l1)`, `r0(l1)` that give \
         the second, `l2 = -r0 / r1`.",
    );
    let names = input_names();
    let e = k.input_array(
        "e",
        &names,
        "`[a12, b12, c12, d12, a13, b13, c13, d13, a23, b23, c23, d23]`: the coefficients of \
         `E12`, `E13`, `E23`",
    );
    let l1: Var = k.ring.add("__l1");
    let l2: Var = k.ring.add("__l2");
    let l3: Var = k.ring.add("__l3");
    let (p1v, p2v, p3v) = (Poly::var(l1), Poly::var(l2), Poly::var(l3));
    let e12 = quadric(&e[0..4], &p1v, &p2v);
    let e13 = quadric(&e[4..8], &p1v, &p3v);
    let e23 = quadric(&e[8..12], &p2v, &p3v);

    // Step 1: E13, E23 as monic quadratics in l3.
    let c13 = e13.collect(l3);
    let c23 = e23.collect(l3);
    assert_eq!(c13.len(), 3, "E13 is quadratic in l3");
    assert_eq!(c23.len(), 3, "E23 is quadratic in l3");
    assert_eq!(c13[2], Poly::int(1), "E13 is monic in l3");
    assert_eq!(c23[2], Poly::int(1), "E23 is monic in l3");
    let (p1, q1, p2, q2) = (&c13[1], &c13[0], &c23[1], &c23[0]);
    let dq = q1.sub(q2);
    let dp = p1.sub(p2);
    let r = dq.mul(&dq).add(&dp.mul(&p1.mul(q2).sub(&p2.mul(q1))));

    // Step 2: R modulo E12 in l2.
    let c12 = e12.collect(l2);
    assert_eq!(c12.len(), 3, "E12 is quadratic in l2");
    assert_eq!(c12[2], Poly::int(1), "E12 is monic in l2");
    let (pp, qq) = (&c12[1], &c12[0]);
    let [r0, r1] = reduce_mod_monic_quadratic(&UPoly::from_poly(&r, l2), pp, qq);

    // As polynomials in l1 with coefficients in the inputs, each coefficient named.
    let r0u = k.define_upoly("r0", &UPoly::from_poly(&r0, l1));
    let r1u = k.define_upoly("r1", &UPoly::from_poly(&r1, l1));
    let ppu = UPoly::from_poly(pp, l1);
    let qqu = UPoly::from_poly(qq, l1);
    assert!(r0u.degree() <= 4 && r1u.degree() <= 3, "r0, r1 degrees");

    // Step 3: the octic.
    let f = r0u
        .mul(&r0u)
        .sub(&ppu.mul(&r0u).mul(&r1u))
        .add(&qqu.mul(&r1u).mul(&r1u));
    assert!(f.degree() <= 8, "F is an octic");
    for n in 0..9 {
        k.output(&format!("f{n}"), f.coeff(n));
    }
    for n in 0..4 {
        k.output(&format!("r1_{n}"), r1u.coeff(n));
    }
    for n in 0..5 {
        k.output(&format!("r0_{n}"), r0u.coeff(n));
    }
    k.output_doc =
        "`[f0, ..., f8, r1_0, ..., r1_3, r0_0, ..., r0_4]`: the coefficients of `F`, `r1` \
                    and `r0` in ascending powers of `l1`."
            .into();
    k
}
