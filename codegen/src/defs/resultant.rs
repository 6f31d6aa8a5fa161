//! Hidden-variable resultants of the null-space cases (docs/algorithm.md, `nullspace` cases 2-4,
//! section 4 G4-G7).
//!
//! Cases 2 and 3 minimise a bivariate quartic cost `C(x, y)`; its stationary points solve
//! `dC/dx = dC/dy = 0`, two cubics in `x` with coefficients polynomial in the hidden `y`. Their
//! resultant in `x` is the 6x6 Sylvester determinant; it is emitted as the 3x3 Bezout determinant
//! with polynomial entries in `y`, evaluated by cofactor expansion with the products unrolled
//! (`det Bezout = -det Sylvester`, so the sign is flipped to return the Sylvester resultant
//! itself). Case 4 eliminates two unknowns of three quadrics and returns the degree-8
//! `det M(k1)`. All equations are derived here symbolically from the costs and constraints.

use crate::poly::{det_bareiss, q, Poly, Var};
use crate::program::{det3_upoly, Kernel, UPoly};

const DEF: &str = "codegen/src/defs/resultant.rs";

/// Cubic `x` coefficients (ascending, as [`UPoly`]s in the hidden variable) of `p`, a
/// polynomial in `x` and `y` of degree <= 3 in `x`.
fn cubic_in_x(p: &Poly, x: Var, y: Var) -> [UPoly; 4] {
    let cx = p.collect(x);
    assert!(cx.len() <= 4, "not a cubic in x");
    std::array::from_fn(|n| UPoly::from_poly(&cx.get(n).cloned().unwrap_or_default(), y))
}

/// The 6x6 Sylvester matrix (eq. 22) of two cubics in `x` (coefficients ascending), entries
/// polynomials. Rows: the first cubic times x^2, x, 1, then the second.
pub fn sylvester6(p: &[Poly; 4], qq: &[Poly; 4]) -> Vec<Vec<Poly>> {
    let mut rows = Vec::new();
    for c in [p, qq] {
        for shift in 0..3 {
            let mut row = vec![Poly::zero(); 6];
            for n in 0..4 {
                // descending powers x^5 .. x^0 in columns 0..5; x^(n + 2 - shift)
                row[5 - (n + 2 - shift)] = c[n].clone();
            }
            rows.push(row);
        }
    }
    rows
}

/// `det Sylvester(p, q)` (exact, Bareiss); used to check the emitted Bezout form.
pub fn sylvester_resultant(p: &[Poly; 4], qq: &[Poly; 4]) -> Poly {
    det_bareiss(&sylvester6(p, qq))
}

/// The resultant in `x` of two cubics whose `x`-coefficients are [`UPoly`]s in `y`, as the
/// Bezout determinant (docs/algorithm.md G7) with every intermediate coefficient named in `k`;
/// returned with the Sylvester sign (`-det Bez`).
fn resultant_bezout(k: &mut Kernel, p: &[UPoly; 4], qq: &[UPoly; 4]) -> UPoly {
    let mut br = |i: usize, j: usize| {
        let b = p[i].mul(&qq[j]).sub(&p[j].mul(&qq[i]));
        k.define_upoly(&format!("br{i}{j}"), &b)
    };
    let (b10, b20, b30, b21, b31, b32) =
        (br(1, 0), br(2, 0), br(3, 0), br(2, 1), br(3, 1), br(3, 2));
    let mid = b21.add(&b30);
    let bez = [
        [b10, b20.clone(), b30.clone()],
        [b20, mid, b31.clone()],
        [b30, b31, b32],
    ];
    det3_upoly(k, "bez", &bez).scale(&q(-1))
}

/// The cost of case 2, `C2(x, y) = |A a - b|^2` with `a = [x^2, x y, y^2]`, written through
/// `Q = A^T A` (6 symbols) and `p = A^T b` (3 symbols): `a^T Q a - 2 p^T a + b^T b` (the
/// constant `b^T b` does not enter the gradient and is dropped).
fn case2_cost(k: &mut Kernel) -> (Poly, Var, Var) {
    let qn: Vec<String> = ["q00", "q01", "q02", "q11", "q12", "q22"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let qv = k.input_array(
        "q",
        &qn,
        "`Q = A^T A` (symmetric 3x3) as `[Q00, Q01, Q02, Q11, Q12, Q22]`",
    );
    let pv = k.input_array(
        "p",
        &["p0".into(), "p1".into(), "p2".into()],
        "`p = A^T b` as `[p0, p1, p2]`",
    );
    let x = k.ring.add("__x");
    let y = k.ring.add("__y");
    let (xp, yp) = (Poly::var(x), Poly::var(y));
    let a = [xp.mul(&xp), xp.mul(&yp), yp.mul(&yp)];
    let qm = |i: usize, j: usize| {
        let (i, j) = (i.min(j), i.max(j));
        let idx = [[0, 1, 2], [1, 3, 4], [2, 4, 5]][i][j];
        qv[idx].clone()
    };
    let mut c = Poly::zero();
    for i in 0..3 {
        for j in 0..3 {
            c = c.add(&qm(i, j).mul(&a[i]).mul(&a[j]));
        }
        c = c.sub(&pv[i].mul(&a[i]).scale(&q(2)));
    }
    (c, x, y)
}

/// The quartic of case 3 in (x, y) = (k1, k2) from its 15 coefficients (input `c`, G5 order).
fn case3_cost(k: &mut Kernel) -> (Poly, Var, Var) {
    let order = case3_monomials();
    let names: Vec<String> = order.iter().map(|(i, j)| format!("c{i}{j}")).collect();
    let cv = k.input_array(
        "c",
        &names,
        "the 15 coefficients `c_ij` of `k1^i k2^j` in `CASE3_MONOMIALS` order",
    );
    let x = k.ring.add("__x");
    let y = k.ring.add("__y");
    let mut c = Poly::zero();
    for ((i, j), ci) in order.iter().zip(&cv) {
        c = c.add(&ci.mul(&Poly::var(x).pow(*i)).mul(&Poly::var(y).pow(*j)));
    }
    (c, x, y)
}

/// Exponents (i, j) of `k1^i k2^j` in G5 order: (4,0), (3,1), ..., (0,0).
pub fn case3_monomials() -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for d in (0..=4u32).rev() {
        for i in (0..=d).rev() {
            out.push((i, d - i));
        }
    }
    out
}

/// Which case-2/3 kernel.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Case {
    /// Case 2 (two null vectors; odd resultant).
    Two,
    /// Case 3 (three null vectors).
    Three,
}

fn cost_for(k: &mut Kernel, case: Case) -> (Poly, Var, Var) {
    match case {
        Case::Two => case2_cost(k),
        Case::Three => case3_cost(k),
    }
}

/// G4 / G5: resultant of the two gradient cubics in the hidden variable `y`.
pub fn resultant(case: Case) -> Kernel {
    let name = match case {
        Case::Two => "case2_resultant",
        Case::Three => "case3_resultant",
    };
    let mut k = Kernel::new(name, DEF);
    let (c, x, y) = cost_for(&mut k, case);
    let g1 = cubic_in_x(&c.derivative(x), x, y);
    let g2 = cubic_in_x(&c.derivative(y), x, y);
    let res = resultant_bezout(&mut k, &g1, &g2);
    match case {
        Case::Two => {
            k.doc(
                "Case 2 of EOPnP (docs/algorithm.md, `nullspace` case 2, G4): `r = x v1 + y v2` minimises \
                   `C2(x, y) = |A a - b|^2`, `a = [x^2, x y, y^2]`. The stationary points solve \
                   `g1 = dC2/dx = 0`, `g2 = dC2/dy = 0`, cubics in `x`; their resultant in `x` \
                   (the 6x6 Sylvester determinant of eq. 22) is odd of degree 9 in the hidden \
                   `y`: `k1 y + k3 y^3 + k5 y^5 + k7 y^7 + k9 y^9` (eq. 23), i.e. the quartic \
                   `k1 + k3 beta + k5 beta^2 + k7 beta^3 + k9 beta^4` in `beta = y^2` (eq. 24).",
            );
            k.doc(
                "Evaluated structurally: the 3x3 Bezout matrix of `g1, g2` (entries polynomial \
                   in `y`), its determinant by cofactor expansion with the polynomial products \
                   unrolled, sign flipped (`det Bezout = -det Sylvester`).",
            );
            for kk in [1usize, 3, 5, 7, 9] {
                k.output(&format!("k{kk}"), res.coeff(kk));
            }
            k.output_doc = "`[k1, k3, k5, k7, k9]`: the quartic in `beta = y^2`, ascending.".into();
        }
        Case::Three => {
            k.doc(
                "Case 3 of EOPnP (docs/algorithm.md, `nullspace` case 3, G5): `r = v1 + k1 v2 + k2 v3` minimises \
                   the bivariate quartic `C3(k1, k2) = |B k|^2`. With `x = k1` and the hidden \
                   `y = k2`, `dC3/dx` and `dC3/dy` are cubics in `x`; their resultant in `x` (the \
                   6x6 Sylvester determinant) has full degree 9 in `y`.",
            );
            k.doc(
                "Evaluated structurally: the 3x3 Bezout matrix (entries polynomial in `y`), its \
                   determinant by cofactor expansion with the polynomial products unrolled, sign \
                   flipped (`det Bezout = -det Sylvester`).",
            );
            for i in 0..10 {
                k.output(&format!("res{i}"), res.coeff(i));
            }
            k.output_doc = "`[r0, ..., r9]`: coefficients of `y^0 .. y^9`, ascending.".into();
            let elems = case3_monomials()
                .iter()
                .map(|(i, j)| format!("[{i}, {j}]"))
                .collect();
            k.table(
                "CASE3_MONOMIALS",
                "Exponents `[i, j]` of `k1^i k2^j` for the 15 coefficients of the case-3 quartic \
                 (docs/algorithm.md G5 order).",
                "[u8; 2]",
                elems,
            );
        }
    }
    k
}

/// G4 / G5 back-substitution: the gradient cubics in `x` at a numeric hidden `y`.
pub fn cubics(case: Case) -> Kernel {
    let name = match case {
        Case::Two => "case2_cubics",
        Case::Three => "case3_cubics",
    };
    let mut k = Kernel::new(name, DEF);
    let (c, x, yi) = cost_for(&mut k, case);
    let y = k.input_scalar("y", "the hidden variable (a root of the resultant)");
    k.doc(&format!(
        "Back-substitution for case {n} of EOPnP (docs/algorithm.md, `nullspace` case {n}): the two gradient cubics \
         `dC/dx` and `dC/dy` as polynomials in `x` at the given hidden `y`.",
        n = if case == Case::Two { 2 } else { 3 },
    ));
    let grads = [c.derivative(x), c.derivative(yi)];
    for (gi, g) in grads.iter().enumerate() {
        let cx = g.substitute(yi, &y).collect(x);
        for n in 0..4 {
            k.output(
                &format!("g{}_{n}", gi + 1),
                cx.get(n).cloned().unwrap_or_default(),
            );
        }
    }
    k.output_doc = "`[a0, a1, a2, a3, b0, b1, b2, b3]`: `dC/dx = a0 + a1 x + a2 x^2 + a3 x^3` and \
                    `dC/dy = b0 + b1 x + b2 x^2 + b3 x^3` at `y`."
        .into();
    k
}

/// Case 3 input: the 15 quartic coefficients `c_ij` from `H = Bm^T Bm` (symmetric 6x6, 21
/// entries) with `k = [k1^2, k2^2, k1 k2, k1, k2, 1]`.
pub fn case3_quartic() -> Kernel {
    let mut k = Kernel::new("case3_quartic", DEF);
    k.doc(
        "Case 3 of EOPnP (docs/algorithm.md, `nullspace` case 3): the coefficients of \
           `C3(k1, k2) = k^T H k`, `k = [k1^2, k2^2, k1 k2, k1, k2, 1]`, from the symmetric 6x6 \
           `H = Bm^T Bm`.",
    );
    let mut names = Vec::new();
    for i in 0..6 {
        for j in i..6 {
            names.push(format!("h{i}{j}"));
        }
    }
    let hv = k.input_array(
        "h",
        &names,
        "the 21 entries `H[i][j]`, `i <= j`, row by row: (0,0), (0,1), ..., (5,5)",
    );
    let hm = |i: usize, j: usize| {
        let (i, j) = (i.min(j), i.max(j));
        let pos = names
            .iter()
            .position(|n| *n == format!("h{i}{j}"))
            .expect("entry");
        hv[pos].clone()
    };
    let x = k.ring.add("__x");
    let y = k.ring.add("__y");
    let (xp, yp) = (Poly::var(x), Poly::var(y));
    let kv = [
        xp.mul(&xp),
        yp.mul(&yp),
        xp.mul(&yp),
        xp.clone(),
        yp.clone(),
        Poly::int(1),
    ];
    let mut c = Poly::zero();
    for i in 0..6 {
        for j in 0..6 {
            c = c.add(&hm(i, j).mul(&kv[i]).mul(&kv[j]));
        }
    }
    let cx = c.collect(x);
    for (i, j) in case3_monomials() {
        let coeff = cx
            .get(i as usize)
            .map(|p| p.collect(y).get(j as usize).cloned().unwrap_or_default())
            .unwrap_or_default();
        k.output(&format!("c{i}{j}"), coeff);
    }
    k.output_doc = "The 15 coefficients `c_ij` in `CASE3_MONOMIALS` order.".into();
    k
}

/// Names of the 21 case-4 inputs `t[i][j][n]` (coefficient of `k1^n` in `T_ij`, `n <= 1` for
/// `j = 0, 1` and `n <= 2` for `j = 2`), in order i, j, n.
pub fn case4_input_names() -> Vec<(usize, usize, usize, String)> {
    let mut out = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            let deg = if j == 2 { 2 } else { 1 };
            for n in 0..=deg {
                out.push((i, j, n, format!("t{i}{j}{n}")));
            }
        }
    }
    out
}

/// Builds the case-4 matrix M(k1) symbolically inside `k`; returns its entries as [`UPoly`]s in
/// k1 (coefficients polynomials in the 21 inputs).
///
/// Derivation (docs/algorithm.md, `nullspace` case 4): with `z = [k2^2, k3^2, k2 k3] = T(k1) y`,
/// `y = [k2, k3, 1]`, the monomial identities `k3 z1 - k2 z3 = 0`, `k3 z3 - k2 z2 = 0` and
/// `z3^2 - z1 z2 = 0` are polynomials of degree <= 2 in (k2, k3); replacing every quadratic
/// monomial by its T-expression makes each one linear in y. That reduction is done here by
/// substitution.
fn case4_matrix_upolys(k: &mut Kernel) -> (Vec<Vec<UPoly>>, Var) {
    let names = case4_input_names();
    let tv = k.input_array(
        "t",
        &names
            .iter()
            .map(|(_, _, _, n)| n.clone())
            .collect::<Vec<_>>(),
        "`T(k1)` as 21 numbers `t[i][j][n]` = coefficient of `k1^n` in `T_ij` \
         (`n <= 1` for `j = 0, 1`; `n <= 2` for `j = 2`), in the order of `CASE4_T_LAYOUT`",
    );
    let k1 = k.ring.add("__k1");
    let k2 = k.ring.add("__k2");
    let k3 = k.ring.add("__k3");
    let k1p = Poly::var(k1);
    // T_ij(k1)
    let mut t: Vec<Vec<Poly>> = vec![vec![Poly::zero(); 3]; 3];
    for ((i, j, n, _), v) in names.iter().zip(&tv) {
        t[*i][*j] = t[*i][*j].add(&v.mul(&k1p.pow(*n as u32)));
    }
    let y = [Poly::var(k2), Poly::var(k3), Poly::int(1)];
    let dot =
        |row: &[Poly]| -> Poly { (0..3).fold(Poly::zero(), |acc, j| acc.add(&row[j].mul(&y[j]))) };
    let z: Vec<Poly> = (0..3).map(|i| dot(&t[i])).collect(); // z_i = T_i . y
                                                             // Reduce a polynomial of degree <= 2 in (k2, k3): k2^2 -> z0, k3^2 -> z1, k2 k3 -> z2.
    let reduce = |p: &Poly| -> Poly {
        let mut out = Poly::zero();
        for (m, c) in &p.terms {
            let (rest, e2) = m.split_var(k2);
            let (rest, e3) = rest.split_var(k3);
            let mut coef = Poly::zero();
            coef.add_term(rest, *c);
            let factor = match (e2, e3) {
                (2, 0) => z[0].clone(),
                (0, 2) => z[1].clone(),
                (1, 1) => z[2].clone(),
                (1, 0) => y[0].clone(),
                (0, 1) => y[1].clone(),
                (0, 0) => Poly::int(1),
                _ => panic!("case 4 reduction: degree > 2 in (k2, k3)"),
            };
            out = out.add(&coef.mul(&factor));
        }
        out
    };
    // Each identity has cubic monomials on both sides that cancel identically; write them with
    // one quadratic factor already replaced, then reduce the remaining quadratic monomials.
    let id1 = Poly::var(k3).mul(&z[0]).sub(&Poly::var(k2).mul(&z[2])); // k3 z1 - k2 z3
    let id2 = Poly::var(k3).mul(&z[2]).sub(&Poly::var(k2).mul(&z[1])); // k3 z3 - k2 z2
    let id3 = z[2].mul(&z[2]).sub(&z[0].mul(&z[1])); //                   z3^2 - z1 z2
    let mut rows = Vec::new();
    for id in [id1, id2, id3] {
        let lin = reduce(&id);
        // coefficients of k2, k3, 1
        let c2 = lin.collect(k2);
        let c3 = c2.first().cloned().unwrap_or_default().collect(k3);
        let e0 = c2.get(1).cloned().unwrap_or_default();
        assert!(
            c2.len() <= 2 && e0.degree_in(k3) == 0,
            "row not linear in y"
        );
        let e1 = c3.get(1).cloned().unwrap_or_default();
        let e2 = c3.first().cloned().unwrap_or_default();
        assert!(c3.len() <= 2, "row not linear in y");
        rows.push(
            [e0, e1, e2]
                .iter()
                .map(|p| UPoly::from_poly(p, k1))
                .collect::<Vec<_>>(),
        );
    }
    (rows, k1)
}

/// G6: the entries of M(k1), each padded to 5 coefficients.
pub fn case4_matrix() -> Kernel {
    let mut k = Kernel::new("case4_matrix", DEF);
    k.doc(
        "Case 4 of EOPnP (docs/algorithm.md, `nullspace` case 4, G6): the 3x3 matrix `M(k1)` of the three-quadrics \
           system after hiding `k1`, linear in `y = [k2, k3, 1]`: `M(k1) y = 0` at a solution. \
           Rows come from the monomial identities `k3 z1 = k2 z3`, `k3 z3 = k2 z2`, \
           `z3^2 = z1 z2` with `z = [k2^2, k3^2, k2 k3] = T(k1) y`, derived symbolically.",
    );
    let (rows, _) = case4_matrix_upolys(&mut k);
    for (i, row) in rows.iter().enumerate() {
        for (j, e) in row.iter().enumerate() {
            for n in 0..5 {
                k.output(&format!("m{i}{j}_{n}"), e.coeff(n));
            }
        }
    }
    k.output_doc = "45 numbers: entry `(i, j)` of `M(k1)` is `sum_n out[(3 i + j) * 5 + n] k1^n`, \
                    `n = 0..4` (entry degrees `[[2, 2, 3], [2, 2, 3], [3, 3, 4]]`, zero padded)."
        .into();
    let elems = case4_input_names()
        .iter()
        .map(|(i, j, n, _)| format!("[{i}, {j}, {n}]"))
        .collect();
    k.table(
        "CASE4_T_LAYOUT",
        "`[i, j, n]` of each input element of the case-4 kernels: coefficient of `k1^n` in \
         `T_ij(k1)`.",
        "[u8; 3]",
        elems,
    );
    k
}

/// G6: `det M(k1)`, degree 8, by cofactor expansion of the polynomial entries.
pub fn case4_determinant() -> Kernel {
    let mut k = Kernel::new("case4_determinant", DEF);
    k.doc(
        "Case 4 of EOPnP (docs/algorithm.md, `nullspace` case 4, G6): the coefficients of `det M(k1)`, a polynomial \
           of degree 8 in the hidden `k1` (eq. 34). Evaluated structurally: the entries of \
           `M(k1)` (see [`case4_matrix`]) as polynomials in `k1`, then the 3x3 determinant by \
           cofactor expansion with the polynomial products unrolled.",
    );
    let (rows, _) = case4_matrix_upolys(&mut k);
    let mut named: Vec<Vec<UPoly>> = Vec::new();
    for (i, row) in rows.iter().enumerate() {
        named.push(
            row.iter()
                .enumerate()
                .map(|(j, e)| k.define_upoly(&format!("m{i}{j}"), e))
                .collect(),
        );
    }
    let a: [[UPoly; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| named[i][j].clone()));
    let det = det3_upoly(&mut k, "det", &a);
    for n in 0..9 {
        k.output(&format!("d{n}"), det.coeff(n));
    }
    k.output_doc = "`[d0, ..., d8]`: coefficients of `k1^0 .. k1^8`, ascending.".into();
    k
}
