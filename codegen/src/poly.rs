//! Sparse multivariate polynomials with exact rational coefficients.
//!
//! A [`Poly`] is a map from [`Mono`] (a sparse exponent vector over variable ids) to a
//! non-zero rational coefficient ([`Q`]). Variables are plain `u16` ids; their names live in
//! the [`crate::program::Ring`] of the kernel being defined. All maps are `BTreeMap`s, so every
//! iteration order (and therefore every emitted file) is deterministic.
//!
//! No floating point is used here: coefficients are `Ratio<i128>` with checked arithmetic, and an
//! overflow is a bug in a definition, reported by a panic at build time.

use num_integer::Integer;
use num_rational::Ratio;
use num_traits::{CheckedAdd, CheckedMul, One, Signed, Zero};
use std::cmp::Ordering;
use std::collections::BTreeMap;

/// Exact rational coefficient.
pub type Q = Ratio<i128>;

/// Variable id (index into the kernel's ring of names).
pub type Var = u16;

/// A monomial: `(variable, exponent)` pairs sorted by variable id, exponents >= 1.
#[derive(Clone, PartialEq, Eq, Hash, Debug, Default)]
pub struct Mono(pub Vec<(Var, u32)>);

impl Mono {
    /// The monomial 1.
    pub fn one() -> Mono {
        Mono(Vec::new())
    }

    /// The monomial `v`.
    pub fn var(v: Var) -> Mono {
        Mono(vec![(v, 1)])
    }

    /// Total degree.
    pub fn degree(&self) -> u32 {
        self.0.iter().map(|&(_, e)| e).sum()
    }

    /// Exponent of `v`.
    pub fn exp(&self, v: Var) -> u32 {
        self.0
            .iter()
            .find(|&&(w, _)| w == v)
            .map(|&(_, e)| e)
            .unwrap_or(0)
    }

    /// Product of two monomials.
    pub fn mul(&self, other: &Mono) -> Mono {
        let (a, b) = (&self.0, &other.0);
        let mut out = Vec::with_capacity(a.len() + b.len());
        let (mut i, mut j) = (0, 0);
        while i < a.len() && j < b.len() {
            match a[i].0.cmp(&b[j].0) {
                Ordering::Less => {
                    out.push(a[i]);
                    i += 1;
                }
                Ordering::Greater => {
                    out.push(b[j]);
                    j += 1;
                }
                Ordering::Equal => {
                    out.push((a[i].0, a[i].1 + b[j].1));
                    i += 1;
                    j += 1;
                }
            }
        }
        out.extend_from_slice(&a[i..]);
        out.extend_from_slice(&b[j..]);
        Mono(out)
    }

    /// `self / other` if `other` divides `self`.
    pub fn div(&self, other: &Mono) -> Option<Mono> {
        if other.0.iter().any(|&(v, d)| self.exp(v) < d) {
            return None;
        }
        let out = self
            .0
            .iter()
            .filter_map(|&(v, e)| {
                let r = e - other.exp(v);
                (r > 0).then_some((v, r))
            })
            .collect();
        Some(Mono(out))
    }

    /// The monomial without variable `v`, and the exponent `v` had.
    pub fn split_var(&self, v: Var) -> (Mono, u32) {
        let e = self.exp(v);
        (
            Mono(self.0.iter().copied().filter(|&(w, _)| w != v).collect()),
            e,
        )
    }

    /// Whether every variable of the monomial satisfies `pred`.
    pub fn all_vars(&self, mut pred: impl FnMut(Var) -> bool) -> bool {
        self.0.iter().all(|&(v, _)| pred(v))
    }
}

/// Graded lexicographic order: higher total degree first; within a degree, a higher power of
/// the lowest-numbered variable first (so `s1^2 > s1 s2 > s2^2`, as in docs/algorithm.md's tables).
impl Ord for Mono {
    fn cmp(&self, other: &Self) -> Ordering {
        other.degree().cmp(&self.degree()).then_with(|| {
            let (a, b) = (&self.0, &other.0);
            for k in 0..a.len().min(b.len()) {
                // smaller variable id present = "more lex-significant"
                match a[k].0.cmp(&b[k].0) {
                    Ordering::Less => return Ordering::Less,
                    Ordering::Greater => return Ordering::Greater,
                    Ordering::Equal => match b[k].1.cmp(&a[k].1) {
                        Ordering::Equal => {}
                        o => return o,
                    },
                }
            }
            a.len().cmp(&b.len())
        })
    }
}

impl PartialOrd for Mono {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// Checked rational sum (a definition that overflows i128 is a bug).
pub fn qadd(a: &Q, b: &Q) -> Q {
    a.checked_add(b)
        .expect("eopnp-codegen: rational overflow in add")
}

/// Checked rational product.
pub fn qmul(a: &Q, b: &Q) -> Q {
    a.checked_mul(b)
        .expect("eopnp-codegen: rational overflow in mul")
}

/// Integer as a rational.
pub fn q(n: i128) -> Q {
    Q::from_integer(n)
}

/// A sparse polynomial with exact rational coefficients.
#[derive(Clone, PartialEq, Eq, Debug, Default)]
pub struct Poly {
    /// Non-zero terms, in graded lexicographic order.
    pub terms: BTreeMap<Mono, Q>,
}

impl Poly {
    /// The zero polynomial.
    pub fn zero() -> Poly {
        Poly::default()
    }

    /// A constant.
    pub fn constant(c: Q) -> Poly {
        let mut p = Poly::zero();
        p.add_term(Mono::one(), c);
        p
    }

    /// An integer constant.
    pub fn int(n: i128) -> Poly {
        Poly::constant(q(n))
    }

    /// The variable `v`.
    pub fn var(v: Var) -> Poly {
        let mut p = Poly::zero();
        p.add_term(Mono::var(v), Q::one());
        p
    }

    /// Whether the polynomial is zero.
    pub fn is_zero(&self) -> bool {
        self.terms.is_empty()
    }

    /// Number of terms.
    pub fn len(&self) -> usize {
        self.terms.len()
    }

    /// Whether there are no terms.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// Adds `c * m` in place.
    pub fn add_term(&mut self, m: Mono, c: Q) {
        if c.is_zero() {
            return;
        }
        match self.terms.get_mut(&m) {
            Some(x) => {
                *x = qadd(x, &c);
                if x.is_zero() {
                    self.terms.remove(&m);
                }
            }
            None => {
                self.terms.insert(m, c);
            }
        }
    }

    /// `self + other`.
    pub fn add(&self, other: &Poly) -> Poly {
        let mut out = self.clone();
        for (m, c) in &other.terms {
            out.add_term(m.clone(), *c);
        }
        out
    }

    /// `self - other`.
    pub fn sub(&self, other: &Poly) -> Poly {
        let mut out = self.clone();
        for (m, c) in &other.terms {
            out.add_term(m.clone(), -*c);
        }
        out
    }

    /// `-self`.
    pub fn neg(&self) -> Poly {
        self.scale(&q(-1))
    }

    /// `c * self`.
    pub fn scale(&self, c: &Q) -> Poly {
        if c.is_zero() {
            return Poly::zero();
        }
        Poly {
            terms: self
                .terms
                .iter()
                .map(|(m, x)| (m.clone(), qmul(x, c)))
                .collect(),
        }
    }

    /// `self * other`.
    pub fn mul(&self, other: &Poly) -> Poly {
        let mut out = Poly::zero();
        for (ma, ca) in &self.terms {
            for (mb, cb) in &other.terms {
                out.add_term(ma.mul(mb), qmul(ca, cb));
            }
        }
        out
    }

    /// `self^n`.
    pub fn pow(&self, n: u32) -> Poly {
        let mut out = Poly::int(1);
        for _ in 0..n {
            out = out.mul(self);
        }
        out
    }

    /// Partial derivative with respect to `v`.
    pub fn derivative(&self, v: Var) -> Poly {
        let mut out = Poly::zero();
        for (m, c) in &self.terms {
            let (rest, e) = m.split_var(v);
            if e == 0 {
                continue;
            }
            let m2 = if e == 1 {
                rest
            } else {
                rest.mul(&Mono(vec![(v, e - 1)]))
            };
            out.add_term(m2, qmul(c, &q(e as i128)));
        }
        out
    }

    /// Substitutes the polynomial `value` for the variable `v`.
    pub fn substitute(&self, v: Var, value: &Poly) -> Poly {
        let mut powers: Vec<Poly> = vec![Poly::int(1)];
        let mut out = Poly::zero();
        for (m, c) in &self.terms {
            let (rest, e) = m.split_var(v);
            while powers.len() <= e as usize {
                let next = powers.last().expect("non-empty").mul(value);
                powers.push(next);
            }
            let mut restp = Poly::zero();
            restp.add_term(rest, *c);
            out = out.add(&restp.mul(&powers[e as usize]));
        }
        out
    }

    /// Substitutes every variable for which `subst` returns a polynomial, in one pass
    /// (simultaneous substitution). Powers are cached per variable.
    pub fn substitute_all(&self, subst: &dyn Fn(Var) -> Option<Poly>) -> Poly {
        let mut cache: BTreeMap<(Var, u32), Poly> = BTreeMap::new();
        let mut out = Poly::zero();
        for (m, c) in &self.terms {
            let mut term = Poly::constant(*c);
            let mut kept = Mono::one();
            for &(v, e) in &m.0 {
                match subst(v) {
                    Some(val) => {
                        let pw = cache.entry((v, e)).or_insert_with(|| val.pow(e));
                        term = term.mul(pw);
                    }
                    None => kept = kept.mul(&Mono(vec![(v, e)])),
                }
            }
            let mut k = Poly::zero();
            k.add_term(kept, Q::one());
            out = out.add(&term.mul(&k));
        }
        out
    }

    /// Collects by powers of `v`: `self = sum_k out[k] v^k` (`out[k]` free of `v`).
    pub fn collect(&self, v: Var) -> Vec<Poly> {
        let mut out: Vec<Poly> = Vec::new();
        for (m, c) in &self.terms {
            let (rest, e) = m.split_var(v);
            while out.len() <= e as usize {
                out.push(Poly::zero());
            }
            out[e as usize].add_term(rest, *c);
        }
        out
    }

    /// Degree in `v` (0 for the zero polynomial).
    pub fn degree_in(&self, v: Var) -> u32 {
        self.terms.keys().map(|m| m.exp(v)).max().unwrap_or(0)
    }

    /// Total degree (0 for the zero polynomial).
    pub fn total_degree(&self) -> u32 {
        self.terms.keys().map(Mono::degree).max().unwrap_or(0)
    }

    /// Exact evaluation at a rational point (`value(v)` for every variable present).
    pub fn eval(&self, value: &dyn Fn(Var) -> Q) -> Q {
        let mut acc = Q::zero();
        for (m, c) in &self.terms {
            let mut t = *c;
            for &(v, e) in &m.0 {
                let x = value(v);
                for _ in 0..e {
                    t = qmul(&t, &x);
                }
            }
            acc = qadd(&acc, &t);
        }
        acc
    }

    /// Leading term in graded lexicographic order.
    pub fn leading(&self) -> Option<(&Mono, &Q)> {
        self.terms.iter().next()
    }

    /// Exact division `self / d`, or `None` if `d` does not divide `self`.
    ///
    /// Multivariate division by leading terms in graded lexicographic order (a monomial order,
    /// so the algorithm terminates); the remainder must be zero.
    pub fn div_exact(&self, d: &Poly) -> Option<Poly> {
        let (lm, lc) = d.leading()?;
        let (lm, lc) = (lm.clone(), *lc);
        let mut rem = self.clone();
        let mut quot = Poly::zero();
        // Each step removes the current leading term of `rem`; bounded by the number of
        // monomials below the starting leading monomial, which is finite.
        while let Some((m, c)) = rem.leading() {
            let qm = m.div(&lm)?;
            let qc = *c / lc;
            let mut t = Poly::zero();
            t.add_term(qm, qc);
            rem = rem.sub(&t.mul(d));
            quot = quot.add(&t);
        }
        Some(quot)
    }

    /// Whether every variable of every term satisfies `pred`.
    pub fn all_vars(&self, mut pred: impl FnMut(Var) -> bool) -> bool {
        self.terms.keys().all(|m| m.all_vars(&mut pred))
    }

    /// If the polynomial is exactly `1 * v`, that variable.
    pub fn as_var(&self) -> Option<Var> {
        if self.terms.len() != 1 {
            return None;
        }
        let (m, c) = self.terms.iter().next()?;
        if c.is_one() && m.0.len() == 1 && m.0[0].1 == 1 {
            Some(m.0[0].0)
        } else {
            None
        }
    }

    /// If the polynomial is a constant (including zero), its value.
    pub fn as_constant(&self) -> Option<Q> {
        match self.terms.len() {
            0 => Some(Q::zero()),
            1 => {
                let (m, c) = self.terms.iter().next()?;
                if m.0.is_empty() {
                    Some(*c)
                } else {
                    None
                }
            }
            _ => None,
        }
    }
}

/// Fraction-free (Bareiss) determinant of a square matrix of polynomials.
///
/// Every division is exact (Sylvester's identity), so entries stay polynomial. A zero pivot is
/// handled by swapping in a later row with a non-zero entry in the pivot column.
pub fn det_bareiss(a: &[Vec<Poly>]) -> Poly {
    let n = a.len();
    assert!(a.iter().all(|r| r.len() == n), "det_bareiss: not square");
    if n == 0 {
        return Poly::int(1);
    }
    let mut m: Vec<Vec<Poly>> = a.to_vec();
    let mut sign = 1i128;
    let mut prev = Poly::int(1);
    for k in 0..n - 1 {
        if m[k][k].is_zero() {
            match (k + 1..n).find(|&i| !m[i][k].is_zero()) {
                Some(i) => {
                    m.swap(i, k);
                    sign = -sign;
                }
                None => return Poly::zero(),
            }
        }
        for i in k + 1..n {
            for j in k + 1..n {
                let num = m[i][j].mul(&m[k][k]).sub(&m[i][k].mul(&m[k][j]));
                m[i][j] = num
                    .div_exact(&prev)
                    .expect("Bareiss division must be exact");
            }
        }
        prev = m[k][k].clone();
    }
    m[n - 1][n - 1].scale(&q(sign))
}

/// Determinant of a 3x3 matrix of polynomials by cofactor expansion along the first row.
pub fn det3(a: &[[Poly; 3]; 3]) -> Poly {
    let minor = |r1: usize, r2: usize, c1: usize, c2: usize| {
        a[r1][c1].mul(&a[r2][c2]).sub(&a[r1][c2].mul(&a[r2][c1]))
    };
    a[0][0]
        .mul(&minor(1, 2, 1, 2))
        .sub(&a[0][1].mul(&minor(1, 2, 0, 2)))
        .add(&a[0][2].mul(&minor(1, 2, 0, 1)))
}

/// Greatest common divisor of the numerators and least common multiple of the denominators
/// of the coefficients (content), used in tests.
pub fn content(p: &Poly) -> Q {
    let mut num = 0i128;
    let mut den = 1i128;
    for c in p.terms.values() {
        num = num.gcd(c.numer());
        den = den.lcm(c.denom());
    }
    Q::new(num.abs(), den)
}

/// Sign helper for coefficients.
pub fn is_negative(c: &Q) -> bool {
    c.is_negative()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn x() -> Poly {
        Poly::var(0)
    }
    fn y() -> Poly {
        Poly::var(1)
    }

    #[test]
    fn arithmetic_and_derivative() {
        // (x + y)^3 = x^3 + 3x^2y + 3xy^2 + y^3
        let p = x().add(&y()).pow(3);
        assert_eq!(p.len(), 4);
        let d = p.derivative(0); // 3(x+y)^2
        assert_eq!(d, x().add(&y()).pow(2).scale(&q(3)));
        // substitution y := 2x gives 27 x^3
        let s = p.substitute(1, &x().scale(&q(2)));
        assert_eq!(s, x().pow(3).scale(&q(27)));
    }

    #[test]
    fn graded_lex_order() {
        let p = x().pow(2).add(&x().mul(&y())).add(&y().pow(2)).add(&x());
        let keys: Vec<_> = p.terms.keys().cloned().collect();
        assert_eq!(keys[0], Mono(vec![(0, 2)]));
        assert_eq!(keys[1], Mono(vec![(0, 1), (1, 1)]));
        assert_eq!(keys[2], Mono(vec![(1, 2)]));
        assert_eq!(keys[3], Mono(vec![(0, 1)]));
    }

    #[test]
    fn exact_division_and_bareiss() {
        let a = x().add(&y()).mul(&x().sub(&y().scale(&q(3))));
        assert_eq!(
            a.div_exact(&x().add(&y())),
            Some(x().sub(&y().scale(&q(3))))
        );
        assert_eq!(x().pow(2).add(&Poly::int(1)).div_exact(&x()), None);
        // Bareiss vs cofactor expansion on a symbolic 3x3
        let v = |i: u16| Poly::var(10 + i);
        let m3: [[Poly; 3]; 3] = [[v(0), v(1), v(2)], [v(3), v(4), v(5)], [v(6), v(7), v(8)]];
        let rows: Vec<Vec<Poly>> = m3.iter().map(|r| r.to_vec()).collect();
        assert_eq!(det_bareiss(&rows), det3(&m3));
        assert_eq!(det3(&m3).len(), 6);
    }

    #[test]
    fn collect_by_variable() {
        let p = x().pow(2).mul(&y()).add(&y().scale(&q(5))).add(&x());
        let c = p.collect(0);
        assert_eq!(c.len(), 3);
        assert_eq!(c[0], y().scale(&q(5)));
        assert_eq!(c[1], Poly::int(1));
        assert_eq!(c[2], y());
    }
}
