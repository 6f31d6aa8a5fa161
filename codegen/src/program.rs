//! A kernel as a straight-line program over exact polynomials.
//!
//! A [`Kernel`] has named inputs (arrays or scalars of `f64`), a sequence of intermediate
//! definitions `name := polynomial in inputs and earlier names`, and outputs (polynomials in
//! inputs and intermediates). Definitions are how structured evaluations (a resultant as a
//! determinant of polynomial entries, products unrolled) stay small; [`Kernel::expanded_outputs`]
//! substitutes every intermediate to get the fully expanded polynomials in the inputs (the
//! "naive" form, used for operation counts and for exact self-checks).

use crate::poly::{Poly, Var, Q};
use std::collections::BTreeMap;

/// Names of the variables of one kernel (inputs first, then intermediates).
#[derive(Clone, Debug, Default)]
pub struct Ring {
    /// `names[v]` is the Rust identifier of variable `v`.
    pub names: Vec<String>,
}

impl Ring {
    /// Adds a variable; panics on a duplicate name (a definition bug).
    pub fn add(&mut self, name: &str) -> Var {
        assert!(
            !self.names.iter().any(|n| n == name),
            "duplicate symbol name {name}"
        );
        self.names.push(name.to_string());
        Var::try_from(self.names.len() - 1).expect("too many symbols")
    }

    /// Whether `name` is taken.
    pub fn has(&self, name: &str) -> bool {
        self.names.iter().any(|n| n == name)
    }
}

/// Shape of an input parameter.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum InputKind {
    /// `name: &[f64; N]`, element `k` bound to `vars[k]`.
    Array,
    /// `name: f64`.
    Scalar,
}

/// One input parameter.
#[derive(Clone, Debug)]
pub struct Input {
    /// Parameter name.
    pub name: String,
    /// One line of documentation (layout of the array).
    pub doc: String,
    /// Variables bound to the elements.
    pub vars: Vec<Var>,
    /// Array or scalar.
    pub kind: InputKind,
}

/// An intermediate definition `var := poly`.
#[derive(Clone, Debug)]
pub struct Def {
    /// The defined variable.
    pub var: Var,
    /// Its value, a polynomial in inputs and earlier definitions.
    pub poly: Poly,
}

/// A constant table exported next to a kernel (e.g. its monomial order).
#[derive(Clone, Debug)]
pub struct Table {
    /// Rust constant name.
    pub name: String,
    /// Documentation.
    pub doc: String,
    /// Element type, e.g. `[u8; 3]`.
    pub elem_ty: String,
    /// Elements as Rust expressions, e.g. `[4, 0, 0]`.
    pub elems: Vec<String>,
}

/// A kernel: one generated function (and its tables).
#[derive(Clone, Debug)]
pub struct Kernel {
    /// Function name (snake case); also the file name `<name>.rs`.
    pub name: String,
    /// Definition file, relative to the workspace root.
    pub definition: String,
    /// Documentation paragraphs (Markdown).
    pub doc: Vec<String>,
    /// Symbol names.
    pub ring: Ring,
    /// Parameters in order.
    pub inputs: Vec<Input>,
    /// Intermediates in evaluation order.
    pub defs: Vec<Def>,
    /// Output names (for the `let` bindings) and values.
    pub outputs: Vec<(String, Poly)>,
    /// Documentation of the output layout.
    pub output_doc: String,
    /// Return a bare `f64` (exactly one output) instead of an array.
    pub scalar_output: bool,
    /// Exported tables.
    pub tables: Vec<Table>,
}

impl Kernel {
    /// Starts a kernel.
    pub fn new(name: &str, definition: &str) -> Kernel {
        Kernel {
            name: name.to_string(),
            definition: definition.to_string(),
            doc: Vec::new(),
            ring: Ring::default(),
            inputs: Vec::new(),
            defs: Vec::new(),
            outputs: Vec::new(),
            output_doc: String::new(),
            scalar_output: false,
            tables: Vec::new(),
        }
    }

    /// Adds a documentation paragraph.
    pub fn doc(&mut self, text: &str) {
        self.doc.push(text.to_string());
    }

    /// Declares an array input `name: &[f64; names.len()]` whose elements are the given symbols.
    pub fn input_array(&mut self, name: &str, names: &[String], doc: &str) -> Vec<Poly> {
        let vars: Vec<Var> = names.iter().map(|n| self.ring.add(n)).collect();
        self.inputs.push(Input {
            name: name.to_string(),
            doc: doc.to_string(),
            vars: vars.clone(),
            kind: InputKind::Array,
        });
        vars.into_iter().map(Poly::var).collect()
    }

    /// Declares a scalar input.
    pub fn input_scalar(&mut self, name: &str, doc: &str) -> Poly {
        let v = self.ring.add(name);
        self.inputs.push(Input {
            name: name.to_string(),
            doc: doc.to_string(),
            vars: vec![v],
            kind: InputKind::Scalar,
        });
        Poly::var(v)
    }

    /// Names `poly` as an intermediate (unless it is already a variable or a constant, which are
    /// returned unchanged) and returns the polynomial standing for it.
    pub fn define(&mut self, name: &str, poly: Poly) -> Poly {
        if poly.as_var().is_some() || poly.as_constant().is_some() {
            return poly;
        }
        let mut unique = name.to_string();
        let mut k = 1;
        while self.ring.has(&unique) {
            unique = format!("{name}_{k}");
            k += 1;
        }
        let v = self.ring.add(&unique);
        self.defs.push(Def { var: v, poly });
        Poly::var(v)
    }

    /// Names every coefficient of a polynomial in the hidden variable (see [`UPoly`]).
    pub fn define_upoly(&mut self, name: &str, p: &UPoly) -> UPoly {
        UPoly(
            p.0.iter()
                .enumerate()
                .map(|(k, c)| self.define(&format!("{name}_{k}"), c.clone()))
                .collect(),
        )
    }

    /// Adds an output.
    pub fn output(&mut self, name: &str, poly: Poly) {
        self.outputs.push((name.to_string(), poly));
    }

    /// Adds a table.
    pub fn table(&mut self, name: &str, doc: &str, elem_ty: &str, elems: Vec<String>) {
        self.tables.push(Table {
            name: name.to_string(),
            doc: doc.to_string(),
            elem_ty: elem_ty.to_string(),
            elems,
        });
    }

    /// Whether `v` is an input variable.
    pub fn is_input(&self, v: Var) -> bool {
        self.inputs.iter().any(|i| i.vars.contains(&v))
    }

    /// The outputs with every intermediate substituted: polynomials in the inputs only.
    pub fn expanded_outputs(&self) -> Vec<Poly> {
        let mut value: BTreeMap<Var, Poly> = BTreeMap::new();
        for d in &self.defs {
            let e = d.poly.substitute_all(&|v| value.get(&v).cloned());
            value.insert(d.var, e);
        }
        self.outputs
            .iter()
            .map(|(_, p)| p.substitute_all(&|v| value.get(&v).cloned()))
            .collect()
    }

    /// Exact evaluation of the outputs through the structured program at a rational input point.
    pub fn eval_structured(&self, input: &dyn Fn(Var) -> Q) -> Vec<Q> {
        let mut value: BTreeMap<Var, Q> = BTreeMap::new();
        for i in &self.inputs {
            for &v in &i.vars {
                value.insert(v, input(v));
            }
        }
        for d in &self.defs {
            let x = d.poly.eval(&|v| value[&v]);
            value.insert(d.var, x);
        }
        self.outputs
            .iter()
            .map(|(_, p)| p.eval(&|v| value[&v]))
            .collect()
    }
}

/// A polynomial in one hidden variable whose coefficients are polynomials in other symbols:
/// `UPoly(c)` stands for `sum_k c[k] y^k` (ascending powers, as in docs/algorithm.md section 4).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UPoly(pub Vec<Poly>);

impl UPoly {
    /// Splits `p` by powers of the variable `y`.
    pub fn from_poly(p: &Poly, y: Var) -> UPoly {
        UPoly(p.collect(y))
    }

    /// The constant polynomial `c`.
    pub fn constant(c: Poly) -> UPoly {
        UPoly(vec![c])
    }

    /// Degree (length - 1 after trimming trailing zeros; 0 for zero).
    pub fn degree(&self) -> usize {
        self.0.iter().rposition(|c| !c.is_zero()).unwrap_or(0)
    }

    /// Coefficient of `y^k` (zero beyond the end).
    pub fn coeff(&self, k: usize) -> Poly {
        self.0.get(k).cloned().unwrap_or_default()
    }

    /// `self + other`.
    pub fn add(&self, other: &UPoly) -> UPoly {
        let n = self.0.len().max(other.0.len());
        UPoly((0..n).map(|k| self.coeff(k).add(&other.coeff(k))).collect())
    }

    /// `self - other`.
    pub fn sub(&self, other: &UPoly) -> UPoly {
        let n = self.0.len().max(other.0.len());
        UPoly((0..n).map(|k| self.coeff(k).sub(&other.coeff(k))).collect())
    }

    /// `c * self` for a rational `c`.
    pub fn scale(&self, c: &Q) -> UPoly {
        UPoly(self.0.iter().map(|p| p.scale(c)).collect())
    }

    /// `self * other`, the product unrolled coefficient by coefficient.
    pub fn mul(&self, other: &UPoly) -> UPoly {
        if self.0.is_empty() || other.0.is_empty() {
            return UPoly(Vec::new());
        }
        let n = self.0.len() + other.0.len() - 1;
        let mut out = vec![Poly::zero(); n];
        for (i, a) in self.0.iter().enumerate() {
            for (j, b) in other.0.iter().enumerate() {
                out[i + j] = out[i + j].add(&a.mul(b));
            }
        }
        UPoly(out)
    }

    /// Back to one polynomial in `y`.
    pub fn to_poly(&self, y: Var) -> Poly {
        let mut out = Poly::zero();
        let yp = Poly::var(y);
        let mut pw = Poly::int(1);
        for c in &self.0 {
            out = out.add(&c.mul(&pw));
            pw = pw.mul(&yp);
        }
        out
    }
}

/// Determinant of a 3x3 matrix of [`UPoly`] entries by cofactor expansion along the first row,
/// naming the coefficients of every 2x2 minor and of the result as intermediates of `k`.
pub fn det3_upoly(k: &mut Kernel, name: &str, a: &[[UPoly; 3]; 3]) -> UPoly {
    let mut minor = |r1: usize, r2: usize, c1: usize, c2: usize, tag: &str| {
        let m = a[r1][c1].mul(&a[r2][c2]).sub(&a[r1][c2].mul(&a[r2][c1]));
        k.define_upoly(&format!("{name}_minor{tag}"), &m)
    };
    let m0 = minor(1, 2, 1, 2, "0");
    let m1 = minor(1, 2, 0, 2, "1");
    let m2 = minor(1, 2, 0, 1, "2");
    a[0][0]
        .mul(&m0)
        .sub(&a[0][1].mul(&m1))
        .add(&a[0][2].mul(&m2))
}
