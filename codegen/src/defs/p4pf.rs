//! The four-point pose with unknown focal length (P4Pf; docs/algorithm.md, G10 "The focal
//! minimal solver"), as three quadrics in three unknowns, and their elimination to an octic
//! (the E3Q3 form of Kukelova, Heller, Bujnak, Fitzgibbon and Pajdla, CVPR 2016).
//!
//! **The quadrics** (`p4pf_quadrics`). Pixels relative to the principal point, `m_i = (u_i,
//! v_i, 1)`; the camera `P = diag(1, 1, w) [R | t]` up to scale, `w = 1 / f`. In the world's
//! affine frame of the four points, `X = X_1 + A Y` with `A = [X_2 - X_1, X_3 - X_1,
//! X_4 - X_1]` (non-coplanar points), the four points are `Y = 0, e_1, e_2, e_3`, so a camera
//! that projects them to `m_i` is `P_Y = [l_2 m_2 - l_1 m_1, l_3 m_3 - l_1 m_1,
//! l_4 m_4 - l_1 m_1 | l_1 m_1]` for scalars `l_i` (`l_i` is `w` times the depth of point `i`,
//! times the scale of `P`). With `l_1 = 1` and `(x, y, z) = (l_2, l_3, l_4)`, the left block
//! `M = M_Y A^-1` must be `s diag(1, 1, w) R`: `M M^T = M_Y G M_Y^T` is `s^2 diag(1, 1, w^2)`,
//! `G = (A^T A)^-1`. With `a`, `b`, `c` the rows of `M_Y` (affine in `x, y, z`) and
//! `<p, q> = p G q^T`, four quadrics vanish at the truth:
//!
//! `q1 = <a, b>`, `q2 = <a, a> - <b, b>`, `q3 = <a, c>`, `q4 = <b, c>`.
//!
//! Four equations in three unknowns: P4Pf is over-determined by one. The solver takes the first
//! three (at most 8 solutions, Bezout) and keeps those that also fit the fourth.
//!
//! **The elimination** (`e3q3_octic`). Three quadrics in `(x, y)` with `z` hidden whose
//! `x^2, xy, y^2` coefficients are constants: solved for those three monomials (a constant 3 x 3
//! system, numerically, by the solver), they read
//!
//! `x^2 = A1 x + B1 y + C1`, `xy = A2 x + B2 y + C2`, `y^2 = A3 x + B3 y + C3`
//!
//! with `A_i`, `B_i` linear and `C_i` quadratic in `z`. The kernel forms three equations linear
//! in `(x, y, 1)`: `L1 = x (xy) - y (x^2)`, `L2 = y (xy) - x (y^2)` and `L3 = y L1` (`x L1` is a combination of the
//! others for every `z`), each with the
//! three monomials replaced by their right-hand sides, so that a solution makes `(x, y, 1)` a
//! null vector of the 3 x 3 matrix `L(z)` of their coefficients; `det L(z)` is an octic in `z`
//! (rows of degrees (2, 2, 3), (2, 2, 3), (3, 3, 4)), whose real roots are the `z` of the
//! solutions, and `(x, y)` follow from `L`'s null vector there.

use crate::poly::{Poly, Var};
use crate::program::{Kernel, UPoly};

const DEF: &str = "codegen/src/defs/p4pf.rs";

/// The monomials of a quadric in `(x, y, z)`, in the order of `p4pf_quadrics`' outputs.
pub const QUADRIC_MONOMIALS: [&str; 10] = ["xx", "xy", "yy", "xz", "yz", "zz", "x", "y", "z", "1"];

/// The exponents of [`QUADRIC_MONOMIALS`].
pub const QUADRIC_EXPONENTS: [[u32; 3]; 10] = [
    [2, 0, 0],
    [1, 1, 0],
    [0, 2, 0],
    [1, 0, 1],
    [0, 1, 1],
    [0, 0, 2],
    [1, 0, 0],
    [0, 1, 0],
    [0, 0, 1],
    [0, 0, 0],
];

/// The coefficient of `x^i y^j z^k` in `p` (a polynomial in the three variables and inputs).
fn coefficient(p: &Poly, (x, y, z): (Var, Var, Var), [i, j, k]: [u32; 3]) -> Poly {
    let cx = p.collect(x);
    let px = cx.get(i as usize).cloned().unwrap_or_else(Poly::zero);
    let cy = px.collect(y);
    let py = cy.get(j as usize).cloned().unwrap_or_else(Poly::zero);
    let cz = py.collect(z);
    cz.get(k as usize).cloned().unwrap_or_else(Poly::zero)
}

/// The four quadrics of P4Pf.
pub fn p4pf_quadrics() -> Kernel {
    let mut k = Kernel::new("p4pf_quadrics", DEF);
    k.doc(
        "The four-point pose with unknown focal length (docs/algorithm.md, G10): from the four \
         image points (relative to the principal point) and `G = (A^T A)^-1` of the world \
         points' affine frame, the coefficients of the four quadrics in `(x, y, z) = (l_2, l_3, \
         l_4)` (`l_1 = 1`): `<a, b>`, `<a, a> - <b, b>`, `<a, c>`, `<b, c>` for the rows `a`, \
         `b`, `c` of `M_Y` and `<p, q> = p G q^T`.",
    );
    let uv = k.input_array(
        "uv",
        &["u1", "v1", "u2", "v2", "u3", "v3", "u4", "v4"].map(String::from),
        "`[u1, v1, ..., u4, v4]`: the image points, relative to the principal point",
    );
    let g = k.input_array(
        "g",
        &["g11", "g12", "g13", "g22", "g23", "g33"].map(String::from),
        "`[g11, g12, g13, g22, g23, g33]`: the upper triangle of `G = (A^T A)^-1`",
    );
    let x = k.ring.add("__x");
    let y = k.ring.add("__y");
    let z = k.ring.add("__z");
    let one = Poly::int(1);
    let l = [
        one.clone(),
        one.add(&Poly::var(x)),
        one.add(&Poly::var(y)),
        one.add(&Poly::var(z)),
    ];
    // Row `r` of M_Y from the image coordinate `coord(i)` of point `i` (1 for the third row).
    let row = |coord: &dyn Fn(usize) -> Poly| -> [Poly; 3] {
        let first = coord(0);
        [1, 2, 3].map(|i| l[i].mul(&coord(i)).sub(&first))
    };
    let a = row(&|i| uv[2 * i].clone());
    let b = row(&|i| uv[2 * i + 1].clone());
    let c = row(&|_| Poly::int(1));
    let gm = [
        [&g[0], &g[1], &g[2]],
        [&g[1], &g[3], &g[4]],
        [&g[2], &g[4], &g[5]],
    ];
    let inner = |p: &[Poly; 3], q: &[Poly; 3]| {
        let mut s = Poly::zero();
        for i in 0..3 {
            for j in 0..3 {
                s = s.add(&p[i].mul(gm[i][j]).mul(&q[j]));
            }
        }
        s
    };
    let quadrics = [
        inner(&a, &b),
        inner(&a, &a).sub(&inner(&b, &b)),
        inner(&a, &c),
        inner(&b, &c),
    ];
    for (n, qd) in quadrics.iter().enumerate() {
        for (mono, e) in QUADRIC_MONOMIALS.iter().zip(QUADRIC_EXPONENTS) {
            k.output(&format!("q{}_{mono}", n + 1), coefficient(qd, (x, y, z), e));
        }
    }
    k.table(
        "P4PF_QUADRIC_EXPONENTS",
        "Exponents `[i, j, k]` of `x^i y^j z^k` for each quadric's 10 coefficients, in the order \
         of `p4pf_quadrics`' outputs (and of `e3q3`'s quadrics).",
        "[u8; 3]",
        QUADRIC_EXPONENTS
            .iter()
            .map(|[i, j, l]| format!("[{i}, {j}, {l}]"))
            .collect(),
    );
    k.output_doc = "`[q1, q2, q3, q4]` (10 each): each quadric's coefficients of `x^2, xy, y^2, \
                    xz, yz, z^2, x, y, z, 1`."
        .into();
    k
}

/// The elimination of three quadrics solved for `x^2, xy, y^2`: the octic `det L(z)` and the
/// matrix `L(z)`.
pub fn e3q3_octic() -> Kernel {
    let mut k = Kernel::new("e3q3_octic", DEF);
    k.doc(
        "Three quadrics in `(x, y, z)` solved for `x^2 = A1 x + B1 y + C1`, `xy = A2 x + B2 y + \
         C2`, `y^2 = A3 x + B3 y + C3` (`A_i`, `B_i` linear, `C_i` quadratic in `z`; \
         docs/algorithm.md, G10): the octic `det L(z)` whose real roots are the solutions' `z`, \
         and the 3 x 3 matrix `L(z)` whose null vector there is `(x, y, 1)`.",
    );
    let mut names = Vec::new();
    for i in 1..=3 {
        for n in [
            format!("a{i}_0"),
            format!("a{i}_1"),
            format!("b{i}_0"),
            format!("b{i}_1"),
            format!("c{i}_0"),
            format!("c{i}_1"),
            format!("c{i}_2"),
        ] {
            names.push(n);
        }
    }
    let m = k.input_array(
        "m",
        &names,
        "`[A1, B1, C1, A2, B2, C2, A3, B3, C3]` in ascending powers of `z` (2, 2 and 3 \
         coefficients each: 21 values)",
    );
    let z = k.ring.add("__z");
    let zp = Poly::var(z);
    let poly = |cs: &[Poly]| {
        let mut p = Poly::zero();
        let mut pow = Poly::int(1);
        for c in cs {
            p = p.add(&c.mul(&pow));
            pow = pow.mul(&zp);
        }
        UPoly::from_poly(&p, z)
    };
    let mut abc = Vec::new();
    for i in 0..3 {
        let r = &m[7 * i..7 * i + 7];
        abc.push((poly(&r[0..2]), poly(&r[2..4]), poly(&r[4..7])));
    }
    let (a1, b1, c1) = abc[0].clone();
    let (a2, b2, c2) = abc[1].clone();
    let (a3, b3, c3) = abc[2].clone();
    // Each L: a combination of x^2, xy, y^2, x, y and 1 whose three quadratic monomials are
    // replaced by their right-hand sides.
    let reduce = |cx2: &UPoly, cxy: &UPoly, cy2: &UPoly, cx: &UPoly, cy: &UPoly, k0: &UPoly| {
        // cx2 x^2 + cxy xy + cy2 y^2 + cx x + cy y + k0, with the three monomials replaced.
        (
            cx2.mul(&a1).add(&cxy.mul(&a2)).add(&cy2.mul(&a3)).add(cx),
            cx2.mul(&b1).add(&cxy.mul(&b2)).add(&cy2.mul(&b3)).add(cy),
            cx2.mul(&c1).add(&cxy.mul(&c2)).add(&cy2.mul(&c3)).add(k0),
        )
    };
    let zero = UPoly(Vec::new());
    let neg = |p: &UPoly| zero.sub(p);
    // x (xy) - y (x^2) = A2 x^2 + (B2 - A1) xy - B1 y^2 + C2 x - C1 y.
    let l1 = reduce(&a2, &b2.sub(&a1), &neg(&b1), &c2, &neg(&c1), &zero);
    // y (xy) - x (y^2) = -A3 x^2 + (A2 - B3) xy + B2 y^2 - C3 x + C2 y.
    let l2 = reduce(&neg(&a3), &a2.sub(&b3), &b2, &neg(&c3), &c2, &zero);
    let rows1 = [
        k.define_upoly("l1x", &l1.0),
        k.define_upoly("l1y", &l1.1),
        k.define_upoly("l11", &l1.2),
    ];
    let rows2 = [
        k.define_upoly("l2x", &l2.0),
        k.define_upoly("l2y", &l2.1),
        k.define_upoly("l21", &l2.2),
    ];
    // L3 = y L1 = l1x xy + l1y y^2 + l11 y.
    let l3 = reduce(&zero, &rows1[0], &rows1[1], &zero, &rows1[2], &zero);
    let rows3 = [
        k.define_upoly("l3x", &l3.0),
        k.define_upoly("l3y", &l3.1),
        k.define_upoly("l31", &l3.2),
    ];
    let rows = [rows1, rows2, rows3];
    let minor = |r1: usize, r2: usize, c1: usize, c2: usize| {
        rows[r1][c1]
            .mul(&rows[r2][c2])
            .sub(&rows[r1][c2].mul(&rows[r2][c1]))
    };
    // The determinant by the first row's cofactors, each minor's coefficients named: the
    // products of polynomials in `z` stay factored (282 multiplications and 237 additions,
    // where the common subexpressions of the expanded determinant took 478 and 387).
    let minors = [
        k.define_upoly("m1", &minor(1, 2, 1, 2)),
        k.define_upoly("m2", &minor(1, 2, 0, 2)),
        k.define_upoly("m3", &minor(1, 2, 0, 1)),
    ];
    let det = rows[0][0]
        .mul(&minors[0])
        .sub(&rows[0][1].mul(&minors[1]))
        .add(&rows[0][2].mul(&minors[2]));
    assert!(det.degree() <= 8, "det L is an octic");
    for n in 0..9 {
        k.output(&format!("d{n}"), det.coeff(n));
    }
    let degrees = [[2, 2, 3], [2, 2, 3], [3, 3, 4]];
    for (r, row) in rows.iter().enumerate() {
        for (c, e) in row.iter().enumerate() {
            assert!(e.degree() <= degrees[r][c], "L's degrees");
            for n in 0..=degrees[r][c] {
                k.output(&format!("l{}{}_{n}", r + 1, ["x", "y", "1"][c]), e.coeff(n));
            }
        }
    }
    k.output_doc = "`[d0, ..., d8]` (the octic, ascending powers of `z`), then `L`'s entries row \
                    by row, each in ascending powers of `z`: degrees (2, 2, 3), (2, 2, 3), \
                    (3, 3, 4), so 3 + 3 + 4, 3 + 3 + 4 and 4 + 4 + 5 coefficients (42 values in \
                    all)."
        .into();
    k
}
