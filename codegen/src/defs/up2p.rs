//! The upright two-point pose (up2p; docs/algorithm.md, G9 "The upright minimal solver"): with the
//! vertical known in both frames and taken as their `y` axis, the rotation is `R_y(theta)`, one
//! unknown angle, and two correspondences fix the pose. Each ray `c_i + l v_i` (centre and
//! direction in the rig frame; `c_i = 0` for one camera) gives two linear equations
//! `a^T (R X_i + t) = a^T c_i` for two vectors `a` orthogonal to `v_i`: four equations
//! `A t = e - b(R)` in `t` (`A` the 4 x 3 matrix of the rows `a_k`, `e_k = a_k^T c_k`,
//! `b_k = a_k^T R X_k`), which have a solution only where `det [A | b(R) - e] = 0`.
//!
//! With the Cayley parameter `s = tan(theta / 2)`, `(1 + s^2) R_y = [[1 - s^2, 0, 2 s],
//! [0, 1 + s^2, 0], [-2 s, 0, 1 - s^2]]`, so `(1 + s^2)` times the last column is quadratic in
//! `s`, and the determinant, expanded along it with the constant cofactors of `A`, is the
//! quadratic `c2 s^2 + c1 s + c0` whose real roots are the rotations. (Homogeneous in
//! `(sin(theta / 2), cos(theta / 2))`: the solver reads a vanishing `c2` as the root
//! `theta = pi`.)

use crate::poly::{q, Poly};
use crate::program::{Kernel, UPoly};

const DEF: &str = "codegen/src/defs/up2p.rs";

/// `det` of a 3 x 3 matrix of polynomials (cofactor expansion along the first row).
fn det3(m: [[&Poly; 3]; 3]) -> Poly {
    let minor = |r1: usize, r2: usize, c1: usize, c2: usize| {
        m[r1][c1].mul(m[r2][c2]).sub(&m[r1][c2].mul(m[r2][c1]))
    };
    m[0][0]
        .mul(&minor(1, 2, 1, 2))
        .sub(&m[0][1].mul(&minor(1, 2, 0, 2)))
        .add(&m[0][2].mul(&minor(1, 2, 0, 1)))
}

/// The quadratic of the upright two-point pose.
pub fn up2p_quadratic() -> Kernel {
    let mut k = Kernel::new("up2p_quadratic", DEF);
    k.doc(
        "The upright two-point pose (docs/algorithm.md, G9): from the four constraint rows \
         `a_k` (two orthogonal to each ray), the two world points (vertical along `y`) and the \
         offsets `e_k = a_k . c_k` of the rays' centres, the coefficients of the quadratic in \
         `s = tan(theta / 2)` whose real roots are the rotations `R_y(theta)`: \
         `det [A | (1 + s^2) (b(R_y) - e)]`, `b_k = a_k . R_y X_k`.",
    );
    let mut names = Vec::new();
    for row in 0..4 {
        for c in ["x", "y", "z"] {
            names.push(format!("a{row}{c}"));
        }
    }
    let a = k.input_array(
        "a",
        &names,
        "`[a0, a1, a2, a3]` (3 each): the constraint rows, `a0`, `a1` of the first \
         correspondence and `a2`, `a3` of the second",
    );
    let p = k.input_array(
        "p",
        &["x1", "y1", "z1", "x2", "y2", "z2"].map(String::from),
        "`[X1, X2]` (3 each): the world points, the vertical along `y`",
    );
    let e = k.input_array(
        "e",
        &["e0", "e1", "e2", "e3"].map(String::from),
        "`[e0, e1, e2, e3]`: `e_k = a_k . c_k`, the rows times their ray's centre (0 for rays \
         through the origin)",
    );
    let s = k.ring.add("__s");
    let sp = Poly::var(s);
    let one = Poly::int(1);
    let s2 = sp.mul(&sp);
    let (cm, cp) = (one.sub(&s2), one.add(&s2));
    // (1 + s^2) R_y X for the world point `i`.
    let rotated = |i: usize| {
        let (x, y, z) = (&p[3 * i], &p[3 * i + 1], &p[3 * i + 2]);
        [
            cm.mul(x).add(&sp.mul(z).scale(&q(2))),
            cp.mul(y),
            cm.mul(z).sub(&sp.mul(x).scale(&q(2))),
        ]
    };
    let points = [rotated(0), rotated(1)];
    // The last column, `(1 + s^2) (a_k . R_y X_k - e_k)`, quadratic in `s`.
    let column: Vec<Poly> = (0..4)
        .map(|row| {
            let x = &points[row / 2];
            let ak = &a[3 * row..3 * row + 3];
            ak[0]
                .mul(&x[0])
                .add(&ak[1].mul(&x[1]))
                .add(&ak[2].mul(&x[2]))
                .sub(&cp.mul(&e[row]))
        })
        .collect();
    // Its cofactors in `det [A | column]`: (-1)^(row + 3) det(A without `row`), each named.
    let mut det = UPoly(Vec::new());
    for (row, col) in column.iter().enumerate() {
        let rest: Vec<usize> = (0..4).filter(|&r| r != row).collect();
        let m = rest
            .iter()
            .map(|&r| [&a[3 * r], &a[3 * r + 1], &a[3 * r + 2]]);
        let m: Vec<[&Poly; 3]> = m.collect();
        let minor = det3([m[0], m[1], m[2]]);
        let sign = if row % 2 == 1 { q(1) } else { q(-1) };
        let cof = k.define(&format!("cof{row}"), minor.scale(&sign));
        det = det.add(&UPoly::from_poly(col, s).mul(&UPoly::constant(cof)));
    }
    assert!(det.degree() <= 2, "the determinant is quadratic in s");
    for n in 0..3 {
        k.output(&format!("c{n}"), det.coeff(n));
    }
    k.output_doc = "`[c0, c1, c2]`: the coefficients of the quadratic in ascending powers of \
                    `s = tan(theta / 2)`."
        .into();
    k
}
