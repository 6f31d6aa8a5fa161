//! The EOPnP cost C(s) = rbar(s)^T M rbar(s) (docs/algorithm.md sections 1, 2 and 4: G1-G3,
//! `newton`).
//!
//! Defined once, from the Cayley map itself: `Rbar(s) = (1 - s^T s) I + 2 [s]x + 2 s s^T`,
//! `rbar = vec(Rbar)` row-major. Every other cost kernel (coefficients, value, gradient, Hessian,
//! planar analogue, the SO(3) local model) is derived from this polynomial by the algebra of
//! [`crate::poly`]; nothing is typed in by hand.

use crate::poly::{q, Mono, Poly, Var};
use crate::program::Kernel;

const DEF: &str = "codegen/src/defs/cost.rs";

/// Entries of r = vec(R) (row-major) in the first two columns of R (docs/algorithm.md, constants
/// and tolerances: `PLANAR`).
pub const PLANAR: [usize; 6] = [0, 1, 3, 4, 6, 7];

/// `rbar(s)` for symbolic `s = (s1, s2, s3)`.
pub fn rbar(s: &[Poly; 3]) -> [Poly; 9] {
    let sts = s[0].mul(&s[0]).add(&s[1].mul(&s[1])).add(&s[2].mul(&s[2]));
    let one_minus = Poly::int(1).sub(&sts);
    // [s]x = [[0, -s3, s2], [s3, 0, -s1], [-s2, s1, 0]]
    let zero = Poly::zero();
    let skew = [
        [zero.clone(), s[2].neg(), s[1].clone()],
        [s[2].clone(), zero.clone(), s[0].neg()],
        [s[1].neg(), s[0].clone(), zero],
    ];
    let mut out: [Poly; 9] = Default::default();
    for i in 0..3 {
        for j in 0..3 {
            let mut e = skew[i][j].scale(&q(2)).add(&s[i].mul(&s[j]).scale(&q(2)));
            if i == j {
                e = e.add(&one_minus);
            }
            out[3 * i + j] = e;
        }
    }
    out
}

/// Names `m00, m01, ..., m88` of the upper triangle of a symmetric 9x9 matrix, in the input order
/// of G1: (0,0), (0,1), ..., (0,8), (1,1), ..., (8,8).
pub fn upper_names(prefix: &str, idx: &[usize]) -> Vec<(usize, usize, String)> {
    let mut out = Vec::new();
    for (a, &i) in idx.iter().enumerate() {
        for &j in &idx[a..] {
            out.push((i, j, format!("{prefix}{i}{j}")));
        }
    }
    out
}

/// Symmetric matrix of symbols from an upper-triangle input (entries outside `idx` are zero).
fn symmetric(upper: &[(usize, usize, String)], vars: &[Poly]) -> Vec<Vec<Poly>> {
    let mut m = vec![vec![Poly::zero(); 9]; 9];
    for ((i, j, _), v) in upper.iter().zip(vars) {
        m[*i][*j] = v.clone();
        m[*j][*i] = v.clone();
    }
    m
}

/// `x^T M x` for a 9-vector of polynomials.
fn quadratic_form(m: &[Vec<Poly>], x: &[Poly; 9]) -> Poly {
    let mut c = Poly::zero();
    for i in 0..9 {
        for j in 0..9 {
            if !m[i][j].is_zero() {
                c = c.add(&m[i][j].mul(&x[i]).mul(&x[j]));
            }
        }
    }
    c
}

/// The 35 monomials of degree <= 4 in (s1, s2, s3), in the order of G1: by degree 4, 3, 2, 1, 0,
/// within a degree by decreasing power of s1, then of s2 (graded lexicographic).
pub fn cost_monomials() -> Vec<[u32; 3]> {
    let mut out = Vec::new();
    for d in (0..=4u32).rev() {
        for a in (0..=d).rev() {
            for b in (0..=d - a).rev() {
                out.push([a, b, d - a - b]);
            }
        }
    }
    out
}

fn mono_s(s_vars: [Var; 3], e: [u32; 3]) -> Mono {
    Mono(
        (0..3)
            .filter(|&k| e[k] > 0)
            .map(|k| (s_vars[k], e[k]))
            .collect(),
    )
}

fn monomial_table(k: &mut Kernel, name: &str) {
    let elems = cost_monomials()
        .iter()
        .map(|e| format!("[{}, {}, {}]", e[0], e[1], e[2]))
        .collect();
    k.table(
        name,
        "Exponents `[a, b, c]` of `s1^a s2^b s3^c` for each of the 35 cost coefficients, in order\n\
         (docs/algorithm.md section 4, G1).",
        "[u8; 3]",
        elems,
    );
}

/// Builds C(s) with symbolic M and s inside `k`; returns (coefficient polynomials in M's
/// symbols, in the 35-monomial order).
fn cost_coefficient_polys(k: &mut Kernel, planar: bool) -> Vec<Poly> {
    let idx: Vec<usize> = if planar {
        PLANAR.to_vec()
    } else {
        (0..9).collect()
    };
    let upper = upper_names("m", &idx);
    let names: Vec<String> = upper.iter().map(|(_, _, n)| n.clone()).collect();
    let doc = if planar {
        "the 21 entries `M[i][j]`, `i <= j`, `i, j` in `PLANAR = [0, 1, 3, 4, 6, 7]`, \
         in the order (0,0), (0,1), (0,3), ..., (7,7)"
    } else {
        "the 45 entries `M[i][j]`, `i <= j`, of the symmetric 9x9 `M`, in the order \
         (0,0), (0,1), ..., (0,8), (1,1), ..., (8,8)"
    };
    let mvars = k.input_array("m", &names, doc);
    let m = symmetric(&upper, &mvars);
    // s is internal here: a scratch ring segment only used to collect coefficients.
    let s_vars = [k.ring.add("__s1"), k.ring.add("__s2"), k.ring.add("__s3")];
    let s = [
        Poly::var(s_vars[0]),
        Poly::var(s_vars[1]),
        Poly::var(s_vars[2]),
    ];
    let c = quadratic_form(&m, &rbar(&s));
    cost_monomials()
        .into_iter()
        .map(|e| {
            let target = mono_s(s_vars, e);
            let mut p = Poly::zero();
            for (mono, coef) in &c.terms {
                let (mut rest, mut ok) = (mono.clone(), true);
                for (kk, &v) in s_vars.iter().enumerate() {
                    let (r, ex) = rest.split_var(v);
                    ok &= ex == e[kk];
                    rest = r;
                }
                if ok {
                    p.add_term(rest, *coef);
                }
            }
            debug_assert!(p.all_vars(|v| !s_vars.contains(&v)), "{target:?}");
            p
        })
        .collect()
}

/// G1 (and G3 with `planar`): the 35 coefficients of C(s) from the entries of M.
pub fn cost_coefficients(planar: bool) -> Kernel {
    let name = if planar {
        "planar_cost_coefficients"
    } else {
        "cost_coefficients"
    };
    let mut k = Kernel::new(name, DEF);
    if planar {
        k.doc(
            "Coefficients of the planar EOPnP cost `C(s) = rbar(s)^T M rbar(s)` when only the \
               first two columns of `R` enter the cost (docs/algorithm.md section 4, G3): `M` is the \
               6x6 restriction of the 9x9 matrix to `PLANAR = [0, 1, 3, 4, 6, 7]`, every other \
               entry zero. All 35 coefficients stay non-zero; the gradient and Hessian at `s` \
               come from [`cost_gradient`] and [`cost_hessian`] (same monomials) or from \
               [`planar_cost_gradient`] / [`planar_cost_hessian`].",
        );
    } else {
        k.doc(
            "Coefficients of the EOPnP cost `C(s) = rbar(s)^T M rbar(s)`, a quartic in the three \
               Cayley (CGR) parameters `s = (s1, s2, s3)` with all 35 monomials of degree <= 4 \
               (docs/algorithm.md section 4, G1; the paper prints only the 15 of degree 4).",
        );
        k.doc("`rbar(s) = vec((1 - s^T s) I + 2 [s]x + 2 s s^T)`, row-major.");
    }
    let coeffs = cost_coefficient_polys(&mut k, planar);
    for (i, p) in coeffs.into_iter().enumerate() {
        k.output(&format!("c{i}"), p);
    }
    k.output_doc = "`c[0..35]`: coefficient of `s1^a s2^b s3^c` with exponents \
                    `COST_MONOMIALS[i]` (degree 4, 3, 2, 1, 0; within a degree by decreasing \
                    power of `s1`, then of `s2`)."
        .to_string();
    if !planar {
        monomial_table(&mut k, "COST_MONOMIALS");
        let elems = upper_names("", &(0..9).collect::<Vec<_>>())
            .iter()
            .map(|(i, j, _)| format!("[{i}, {j}]"))
            .collect();
        k.table(
            "COST_M_UPPER",
            "Position `[i, j]` in `M` of each input element of [`cost_coefficients`] and \
             [`so3_local_model`] (upper triangle, row by row).",
            "[u8; 2]",
            elems,
        );
        let elems = upper_names("", &PLANAR)
            .iter()
            .map(|(i, j, _)| format!("[{i}, {j}]"))
            .collect();
        k.table(
            "PLANAR_M_UPPER",
            "Position `[i, j]` in the 9x9 `M` of each input element of \
             [`planar_cost_coefficients`] and the planar gradient/Hessian kernels.",
            "[u8; 2]",
            elems,
        );
    }
    k
}

/// The cost polynomial in (c, s) for the value / gradient / Hessian kernels.
fn cost_in_c(k: &mut Kernel) -> (Poly, [Var; 3]) {
    let names: Vec<String> = (0..35).map(|i| format!("c{i}")).collect();
    let c = k.input_array(
        "c",
        &names,
        "the 35 cost coefficients in `COST_MONOMIALS` order (from [`cost_coefficients`] or \
         [`planar_cost_coefficients`])",
    );
    let s = k.input_array(
        "s",
        &["s1".into(), "s2".into(), "s3".into()],
        "the CGR parameters",
    );
    let sv = [
        s[0].as_var().expect("var"),
        s[1].as_var().expect("var"),
        s[2].as_var().expect("var"),
    ];
    let mut poly = Poly::zero();
    for (ci, e) in c.iter().zip(cost_monomials()) {
        let mut t = Poly::zero();
        t.add_term(mono_s(sv, e), q(1));
        poly = poly.add(&ci.mul(&t));
    }
    (poly, sv)
}

/// Which derivative of C a kernel returns.
#[derive(Clone, Copy)]
pub enum Order {
    /// C(s).
    Value,
    /// grad C(s).
    Gradient,
    /// The 6 unique entries of hess C(s).
    Hessian,
}

/// Upper-triangle index pairs of a 3x3 symmetric matrix: (0,0), (0,1), (0,2), (1,1), (1,2), (2,2).
pub const SYM3: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];

fn derivatives(poly: &Poly, sv: [Var; 3], order: Order) -> Vec<(String, Poly)> {
    match order {
        Order::Value => vec![("cost".into(), poly.clone())],
        Order::Gradient => (0..3)
            .map(|i| (format!("g{i}"), poly.derivative(sv[i])))
            .collect(),
        Order::Hessian => SYM3
            .iter()
            .map(|&(i, j)| (format!("h{i}{j}"), poly.derivative(sv[i]).derivative(sv[j])))
            .collect(),
    }
}

/// G2: value, gradient or Hessian of C at `s` from the 35 coefficients.
pub fn cost_at(order: Order) -> Kernel {
    let (name, what, out_doc) = match order {
        Order::Value => ("cost", "Value", "`C(s)`."),
        Order::Gradient => (
            "cost_gradient",
            "Gradient",
            "`[dC/ds1, dC/ds2, dC/ds3]` at `s`.",
        ),
        Order::Hessian => (
            "cost_hessian",
            "Hessian",
            "The 6 unique entries of the symmetric Hessian of `C` at `s`: \
             `[H00, H01, H02, H11, H12, H22]`.",
        ),
    };
    let mut k = Kernel::new(name, DEF);
    k.doc(&format!(
        "{what} of the EOPnP cost `C(s) = sum_i c[i] s^COST_MONOMIALS[i]` at `s` \
         (docs/algorithm.md section 4, G2), derived symbolically from the cost polynomial."
    ));
    let (poly, sv) = cost_in_c(&mut k);
    for (n, p) in derivatives(&poly, sv, order) {
        k.output(&n, p);
    }
    k.scalar_output = matches!(order, Order::Value);
    k.output_doc = out_doc.to_string();
    k
}

/// G3 gradient / Hessian: derivatives of the planar cost at `s` directly from the 21 entries of
/// the planar M (coefficients as named intermediates, then the derivative).
pub fn planar_cost_at(order: Order) -> Kernel {
    let (name, out_doc) = match order {
        Order::Gradient => ("planar_cost_gradient", "`[dC/ds1, dC/ds2, dC/ds3]` at `s`."),
        Order::Hessian => (
            "planar_cost_hessian",
            "`[H00, H01, H02, H11, H12, H22]` of the planar cost at `s`.",
        ),
        Order::Value => ("planar_cost", "`C(s)`."),
    };
    let mut k = Kernel::new(name, DEF);
    k.doc(
        "Derivative of the planar EOPnP cost (docs/algorithm.md section 4, G3) at `s`, from the 21 \
           entries of the planar `M`: the 35 coefficients are formed first, then the derivative \
           of `sum_i c[i] s^COST_MONOMIALS[i]`.",
    );
    let coeffs = cost_coefficient_polys(&mut k, true);
    let s = k.input_array(
        "s",
        &["s1".into(), "s2".into(), "s3".into()],
        "the CGR parameters",
    );
    let sv = [
        s[0].as_var().expect("var"),
        s[1].as_var().expect("var"),
        s[2].as_var().expect("var"),
    ];
    let mut poly = Poly::zero();
    for (i, (p, e)) in coeffs.into_iter().zip(cost_monomials()).enumerate() {
        let ci = k.define(&format!("c{i}"), p);
        let mut t = Poly::zero();
        t.add_term(mono_s(sv, e), q(1));
        poly = poly.add(&ci.mul(&t));
    }
    for (n, p) in derivatives(&poly, sv, order) {
        k.output(&n, p);
    }
    k.scalar_output = matches!(order, Order::Value);
    k.output_doc = out_doc.to_string();
    k
}

/// `newton`: the local model of f(R) = vec(R)^T M vec(R) at a rotation R in the CGR chart centred
/// on R (s -> R(s) R): `[f, g0, g1, g2, hc00, hc01, hc02, hc11, hc12, hc22]` = the coefficients
/// c34, c31..c33 and the Hessian of C_k at 0 from c25..c30, for `M_k = D^T M D`,
/// `D = blockdiag(R^T, R^T, R^T)`.
pub fn so3_local_model() -> Kernel {
    let mut k = Kernel::new("so3_local_model", DEF);
    k.doc(
        "Local model of `f(R) = vec(R)^T M vec(R)` at the rotation `R` in the CGR chart \
           centred on `R` (`s -> R(s) R`, docs/algorithm.md, `newton`): the value, gradient and Hessian at \
           `s = 0` of `C_k(s) = rbar(s)^T M_k rbar(s)`, `M_k = D^T M D`, \
           `D = blockdiag(R^T, R^T, R^T)`.",
    );
    k.doc(
        "Since `C_k(s) = (1 + s^T s)^2 f(R(s) R)`, `g` is also the gradient of `f` in the chart \
           and the exact Hessian of `f` is `H_C - 4 f I` (docs/algorithm.md, `newton`, trap T3).",
    );
    let upper = upper_names("m", &(0..9).collect::<Vec<_>>());
    let names: Vec<String> = upper.iter().map(|(_, _, n)| n.clone()).collect();
    let mvars = k.input_array(
        "m",
        &names,
        "the 45 entries `M[i][j]`, `i <= j` (order of `COST_M_UPPER`)",
    );
    let rnames: Vec<String> = (0..3)
        .flat_map(|i| (0..3).map(move |j| format!("r{}{}", i + 1, j + 1)))
        .collect();
    let r = k.input_array(
        "r",
        &rnames,
        "the rotation `R`, row-major (`r11, r12, ..., r33`)",
    );
    let m = symmetric(&upper, &mvars);
    // (M_k)[3a + i][3b + j] = sum_{p, l} R[i][p] M[3a + p][3b + l] R[j][l]
    let mut mk_upper: Vec<Poly> = Vec::new();
    for (ii, jj, _) in &upper {
        let (a, i, b, j) = (ii / 3, ii % 3, jj / 3, jj % 3);
        let mut e = Poly::zero();
        for p in 0..3 {
            for l in 0..3 {
                let t = r[3 * i + p]
                    .mul(&m[3 * a + p][3 * b + l])
                    .mul(&r[3 * j + l]);
                e = e.add(&t);
            }
        }
        mk_upper.push(k.define(&format!("mk{ii}{jj}"), e));
    }
    // Coefficients c25..c34 of the cost for M_k: substitute M_k into the symbolic coefficients.
    let mut scratch = Kernel::new("scratch", DEF);
    let coeff = cost_coefficient_polys(&mut scratch, false);
    let scratch_m: Vec<Var> = scratch.inputs[0].vars.clone();
    let sub = |p: &Poly| {
        p.substitute_all(&|v| {
            scratch_m
                .iter()
                .position(|&w| w == v)
                .map(|i| mk_upper[i].clone())
        })
    };
    let c: Vec<Poly> = (25..35).map(|i| sub(&coeff[i])).collect();
    let two = q(2);
    let outs = [
        ("f", c[9].clone()),
        ("g0", c[6].clone()),
        ("g1", c[7].clone()),
        ("g2", c[8].clone()),
        ("hc00", c[0].scale(&two)),
        ("hc01", c[1].clone()),
        ("hc02", c[2].clone()),
        ("hc11", c[3].scale(&two)),
        ("hc12", c[4].clone()),
        ("hc22", c[5].scale(&two)),
    ];
    for (n, p) in outs {
        k.output(n, p);
    }
    k.output_doc =
        "`[f, g0, g1, g2, hc00, hc01, hc02, hc11, hc12, hc22]`: `f = vec(R)^T M vec(R)`, \
                    the gradient `g` and the Hessian `H_C` (upper triangle) of `C_k` at `s = 0`."
            .to_string();
    k
}

/// The generalized (multi-camera) cost's affine part at a rotation `R` in the same chart as
/// [`so3_local_model`] (`s -> R(s) R`, docs/algorithm.md, generalized EOPnP): rays with centres
/// make the cost `f(R) = vec(R)^T M vec(R) + 2 g^T vec(R) + k`, and in Cayley coordinates
/// `(1 + s^T s)^2 f(R(s) R) = C_k(s) + A_k(s)` with `C_k` the quadratic part's model and
/// `A_k(s) = 2 (1 + s^T s) g_k^T rbar(s) + k (1 + s^T s)^2`, `g_k = D^T g`,
/// `D = blockdiag(R^T, R^T, R^T)`: the value, gradient and Hessian of `A_k` at `s = 0`, to add
/// to [`so3_local_model`]'s.
pub fn so3_local_affine() -> Kernel {
    let mut k = Kernel::new("so3_local_affine", DEF);
    k.doc(
        "The affine part of the generalized cost `f(R) = vec(R)^T M vec(R) + 2 g^T vec(R) + k` \
         (docs/algorithm.md, generalized EOPnP) in the CGR chart centred on `R` (`s -> R(s) R`): \
         the value, gradient and Hessian at `s = 0` of `A_k(s) = 2 (1 + s^T s) g_k^T rbar(s) + \
         k (1 + s^T s)^2`, `g_k = D^T g`, `D = blockdiag(R^T, R^T, R^T)`. Added to \
         `so3_local_model`'s outputs they give the model of the whole cost.",
    );
    let gnames: Vec<String> = (0..9).map(|i| format!("g{i}")).collect();
    let g = k.input_array(
        "g",
        &gnames,
        "the linear term `g` of the cost (9 numbers, the row-major `vec(R)` order)",
    );
    let kk = k.input_scalar("k", "the constant term `k` of the cost");
    let rnames: Vec<String> = (0..3)
        .flat_map(|i| (0..3).map(move |j| format!("r{}{}", i + 1, j + 1)))
        .collect();
    let r = k.input_array(
        "r",
        &rnames,
        "the rotation `R`, row-major (`r11, r12, ..., r33`)",
    );
    // g_k[3a + i] = sum_p R[i][p] g[3a + p]
    let mut gk: Vec<Poly> = Vec::new();
    for a in 0..3 {
        for i in 0..3 {
            let mut e = Poly::zero();
            for p in 0..3 {
                e = e.add(&r[3 * i + p].mul(&g[3 * a + p]));
            }
            gk.push(k.define(&format!("gk{}", 3 * a + i), e));
        }
    }
    let sv = [k.ring.add("__s1"), k.ring.add("__s2"), k.ring.add("__s3")];
    let s = [Poly::var(sv[0]), Poly::var(sv[1]), Poly::var(sv[2])];
    let sts = s[0].mul(&s[0]).add(&s[1].mul(&s[1])).add(&s[2].mul(&s[2]));
    let one_plus = Poly::int(1).add(&sts);
    let rb = rbar(&s);
    let mut lin = Poly::zero();
    for (gi, ri) in gk.iter().zip(rb.iter()) {
        lin = lin.add(&gi.mul(ri));
    }
    let a = one_plus
        .mul(&lin)
        .scale(&q(2))
        .add(&kk.mul(&one_plus.mul(&one_plus)));
    // Value, gradient and Hessian at s = 0: the derivatives with s set to 0.
    let at0 = |p: &Poly| p.substitute_all(&|v| sv.contains(&v).then(Poly::zero));
    let grad: Vec<Poly> = (0..3).map(|i| a.derivative(sv[i])).collect();
    let mut outs = vec![("f".to_string(), at0(&a))];
    for (i, gi) in grad.iter().enumerate() {
        outs.push((format!("g{i}"), at0(gi)));
    }
    for &(i, j) in &SYM3 {
        outs.push((format!("hc{i}{j}"), at0(&grad[i].derivative(sv[j]))));
    }
    for (n, p) in outs {
        k.output(&n, p);
    }
    k.output_doc = "`[f, g0, g1, g2, hc00, hc01, hc02, hc11, hc12, hc22]`: `A_k` (which is \
                    `2 g^T vec(R) + k`), its gradient and its Hessian (upper triangle) at `s = 0`."
        .to_string();
    k
}
