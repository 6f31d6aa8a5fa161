//! Kernel -> straight-line Rust source.
//!
//! The emitter turns a [`Kernel`] into one `pub fn` (plus its tables and an op-count constant),
//! built as a `quote!` token stream and formatted once with `prettyplease`. Common
//! subexpressions are shared in three ways, all deterministic (BTreeMap order, no hashing):
//!
//! 1. monomials: every product of two or more symbols is built once, from an already available
//!    sub-monomial times another available factor (`let s1s2 = s1 * s2;`);
//! 2. sums: within a group of independent definitions, a pair of terms `a + r b` that occurs in
//!    two or more of them (same ratio `r`) becomes one named sum (greedy, most frequent first);
//! 3. coefficients: the terms of each expression are grouped by absolute coefficient, so
//!    `4 a + 4 b - 4 c` costs one multiplication: `4.0 * (a + b - c)`.
//!
//! Only definitions that an output depends on are emitted. Operation counts are reported twice:
//! for the emitted code and for the naive term-by-term evaluation of the fully expanded outputs.

use crate::poly::{Mono, Poly, Var, Q};
use crate::program::{InputKind, Kernel};
use num_traits::{One, Signed};
use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::quote;
use std::collections::{BTreeMap, BTreeSet};

/// Multiplications and additions (subtractions count as additions).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OpCount {
    /// Multiplications (including by constants; divisions of constant rationals are folded).
    pub mul: usize,
    /// Additions and subtractions.
    pub add: usize,
}

impl OpCount {
    /// Total.
    pub fn total(&self) -> usize {
        self.mul + self.add
    }
}

/// The result of emitting a kernel.
#[derive(Clone, Debug)]
pub struct Emitted {
    /// Formatted Rust source of the file `<name>.rs`.
    pub source: String,
    /// Operations of the emitted (CSE) code.
    pub ops: OpCount,
    /// Operations of the naive evaluation of the expanded outputs.
    pub naive: OpCount,
    /// Number of terms of the expanded outputs.
    pub naive_terms: usize,
}

/// Operation count of evaluating `polys` term by term (no sharing at all).
pub fn naive_ops(polys: &[Poly]) -> (usize, OpCount) {
    let mut ops = OpCount::default();
    let mut terms = 0;
    for p in polys {
        terms += p.len();
        ops.add += p.len().saturating_sub(1);
        for (m, c) in &p.terms {
            let d = m.degree() as usize;
            if d >= 1 {
                ops.mul += d - 1;
                if !c.abs().is_one() {
                    ops.mul += 1;
                }
            }
        }
    }
    (terms, ops)
}

fn ident(name: &str) -> Ident {
    Ident::new(name, Span::call_site())
}

fn lit_f64(x: f64) -> Literal {
    Literal::f64_unsuffixed(x)
}

/// A non-negative rational as a Rust expression: `4.0` or `(1.0 / 3.0)`.
fn rational_tokens(c: &Q) -> TokenStream {
    let c = c.abs();
    if c.is_integer() {
        let v = lit_f64(*c.numer() as f64);
        quote!(#v)
    } else {
        let (n, d) = (lit_f64(*c.numer() as f64), lit_f64(*c.denom() as f64));
        quote!((#n / #d))
    }
}

/// An operand of a linear combination.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Atom {
    One,
    Name(String),
}

type Combo = Vec<(Q, Atom)>;

struct Emitter<'k> {
    k: &'k Kernel,
    /// Available monomials (degree >= 1) and the identifier holding their value.
    monos: BTreeMap<Mono, String>,
    /// Identifiers in use.
    taken: BTreeSet<String>,
    lines: Vec<TokenStream>,
    ops: OpCount,
}

impl<'k> Emitter<'k> {
    fn name_of(&self, v: Var) -> &str {
        &self.k.ring.names[v as usize]
    }

    /// Input group of a variable: the index of its input, or one group for all intermediates.
    fn group(&self, v: Var) -> usize {
        self.k
            .inputs
            .iter()
            .position(|i| i.vars.contains(&v))
            .unwrap_or(usize::MAX)
    }

    fn fresh(&mut self, base: &str) -> String {
        let mut name = base.to_string();
        let mut i = 1;
        while self.taken.contains(&name) {
            name = format!("{base}_{i}");
            i += 1;
        }
        self.taken.insert(name.clone());
        name
    }

    fn mono_base_name(&self, m: &Mono) -> String {
        let mut s = String::new();
        for &(v, e) in &m.0 {
            s.push_str(self.name_of(v));
            if e > 1 {
                s.push_str(&format!("pow{e}"));
            }
        }
        if s.len() > 40 {
            "mono".to_string()
        } else {
            s
        }
    }

    /// Makes monomial `m` available, emitting the products it needs.
    fn ensure_mono(&mut self, m: &Mono) -> String {
        if let Some(n) = self.monos.get(m) {
            return n.clone();
        }
        assert!(
            m.degree() >= 2,
            "degree-1 monomials are variables and always bound"
        );
        // Best split: an available divisor of highest degree whose cofactor is also available.
        let mut best: Option<(u32, Mono, Mono)> = None;
        for a in self.monos.keys() {
            if let Some(b) = m.div(a) {
                if b.degree() >= 1 && self.monos.contains_key(&b) {
                    let d = a.degree().max(b.degree());
                    if best.as_ref().is_none_or(|(bd, _, _)| d > *bd) {
                        best = Some((d, a.clone(), b));
                    }
                }
            }
        }
        let (a, b) = match best {
            Some((_, a, b)) => (a, b),
            None => {
                // A monomial over several inputs (e.g. a coefficient times a power of `s`) is
                // split by input first, so each input's part is built once and shared.
                let g0 = self.group(m.0[0].0);
                let (same, other): (Vec<_>, Vec<_>) =
                    m.0.iter().partition(|&&(v, _)| self.group(v) == g0);
                let (a, b) = if !other.is_empty() {
                    (Mono(same), Mono(other))
                } else {
                    // One input: peel off the last variable and build the rest first.
                    let &(v, _) = m.0.last().expect("degree >= 2");
                    let x = Mono::var(v);
                    (m.div(&x).expect("divides"), x)
                };
                for part in [&a, &b] {
                    if part.degree() >= 2 {
                        self.ensure_mono(part);
                    }
                }
                (a, b)
            }
        };
        let (na, nb) = (ident(&self.monos[&a]), ident(&self.monos[&b]));
        let name = self.fresh(&self.mono_base_name(m));
        let id = ident(&name);
        self.lines.push(quote!(let #id = #na * #nb;));
        self.ops.mul += 1;
        self.monos.insert(m.clone(), name.clone());
        name
    }

    fn combo_of(&mut self, p: &Poly) -> Combo {
        // Build monomials lowest degree first so that higher ones can reuse them.
        let mut ms: Vec<&Mono> = p.terms.keys().collect();
        ms.sort_by_key(|m| m.degree());
        for m in ms {
            if m.degree() >= 2 {
                self.ensure_mono(m);
            }
        }
        p.terms
            .iter()
            .map(|(m, c)| {
                let atom = if m.0.is_empty() {
                    Atom::One
                } else {
                    Atom::Name(self.monos[m].clone())
                };
                (*c, atom)
            })
            .collect()
    }

    /// Greedy pair extraction over the combos of one group of independent expressions.
    fn share_sums(&mut self, combos: &mut [Combo]) {
        const MAX_TERMS: usize = 64;
        for _round in 0..100_000 {
            let mut count: BTreeMap<(Atom, Atom, Q), usize> = BTreeMap::new();
            for c in combos.iter() {
                if c.len() < 3 || c.len() > MAX_TERMS {
                    continue; // a 2-term combo gains nothing from naming itself
                }
                for i in 0..c.len() {
                    for j in 0..c.len() {
                        let (ci, ai) = &c[i];
                        let (cj, aj) = &c[j];
                        if ai >= aj || *ai == Atom::One || *aj == Atom::One {
                            continue;
                        }
                        *count
                            .entry((ai.clone(), aj.clone(), *cj / *ci))
                            .or_default() += 1;
                    }
                }
            }
            let Some(((a, b, r), _)) = count
                .into_iter()
                .filter(|(_, n)| *n >= 2)
                .max_by(|x, y| x.1.cmp(&y.1).then_with(|| y.0.cmp(&x.0)))
            else {
                return;
            };
            let (Atom::Name(na), Atom::Name(nb)) = (&a, &b) else {
                unreachable!()
            };
            let sign = if r.is_negative() { "minus" } else { "plus" };
            let scale = if r.abs().is_one() {
                String::new()
            } else if r.abs().is_integer() {
                format!("{}_", r.abs().numer())
            } else {
                format!("{}_{}_", r.abs().numer(), r.abs().denom())
            };
            let base = format!("{na}_{sign}_{scale}{nb}");
            let base = if base.len() > 32 {
                "sum".to_string()
            } else {
                base
            };
            let name = self.fresh(&base);
            let expr = combo_tokens(&[(Q::one(), a.clone()), (r, b.clone())], &mut self.ops);
            let id = ident(&name);
            self.lines.push(quote!(let #id = #expr;));
            for c in combos.iter_mut() {
                if c.len() < 3 || c.len() > MAX_TERMS {
                    continue;
                }
                let ia = c.iter().position(|(_, x)| *x == a);
                let ib = c.iter().position(|(_, x)| *x == b);
                if let (Some(ia), Some(ib)) = (ia, ib) {
                    if c[ib].0 == c[ia].0 * r {
                        c[ia].1 = Atom::Name(name.clone());
                        c.remove(ib);
                    }
                }
            }
        }
    }

    /// Emits `let name = ...;` for each item. `reserved`: the names are ring symbols (already
    /// unique); otherwise fresh names are derived from them.
    fn emit_group(&mut self, items: &[(String, Poly)], reserved: bool) -> Vec<String> {
        let mut combos: Vec<Combo> = items.iter().map(|(_, p)| self.combo_of(p)).collect();
        self.share_sums(&mut combos);
        let mut names = Vec::new();
        for ((name, _), combo) in items.iter().zip(&combos) {
            let expr = combo_tokens(combo, &mut self.ops);
            let n = if reserved {
                name.clone()
            } else {
                self.fresh(name)
            };
            let id = ident(&n);
            self.lines.push(quote!(let #id = #expr;));
            names.push(n);
        }
        names
    }
}

/// Tokens of `sum_i c_i * atom_i`, grouping terms by absolute coefficient; counts its ops.
fn combo_tokens(combo: &[(Q, Atom)], ops: &mut OpCount) -> TokenStream {
    if combo.is_empty() {
        let z = lit_f64(0.0);
        return quote!(#z);
    }
    // Groups keyed by |c| in order of first appearance; the constant term is its own group.
    let mut groups: Vec<(Q, Vec<(bool, Atom)>)> = Vec::new();
    for (c, a) in combo {
        let neg = c.is_negative();
        if *a == Atom::One {
            groups.push((c.abs(), vec![(neg, Atom::One)]));
            continue;
        }
        match groups
            .iter_mut()
            .find(|(g, v)| *g == c.abs() && v[0].1 != Atom::One)
        {
            Some((_, v)) => v.push((neg, a.clone())),
            None => groups.push((c.abs(), vec![(neg, a.clone())])),
        }
    }
    let nterms: usize = groups.iter().map(|(_, v)| v.len()).sum();
    ops.add += nterms - 1;
    // Unit-coefficient groups need no grouping: their atoms are added one by one.
    let groups: Vec<(Q, Vec<(bool, Atom)>)> = groups
        .into_iter()
        .flat_map(|(mag, atoms)| {
            if mag.is_one() && atoms[0].1 != Atom::One {
                atoms
                    .into_iter()
                    .map(|a| (Q::one(), vec![a]))
                    .collect::<Vec<_>>()
            } else {
                vec![(mag, atoms)]
            }
        })
        .collect();
    let mut out = TokenStream::new();
    for (gi, (mag, atoms)) in groups.iter().enumerate() {
        // Normalise so the first atom of the group is positive; the group carries the sign.
        let gneg = atoms[0].0;
        let mut inner = TokenStream::new();
        for (ai, (neg, atom)) in atoms.iter().enumerate() {
            let t = match atom {
                Atom::One => rational_tokens(mag),
                Atom::Name(n) => {
                    let id = ident(n);
                    quote!(#id)
                }
            };
            let rel_neg = *neg != gneg;
            inner = if ai == 0 {
                t
            } else if rel_neg {
                quote!(#inner - #t)
            } else {
                quote!(#inner + #t)
            };
        }
        let is_const = atoms[0].1 == Atom::One;
        let term = if is_const || mag.is_one() {
            if atoms.len() > 1 {
                quote!((#inner))
            } else {
                inner
            }
        } else {
            ops.mul += 1;
            let c = rational_tokens(mag);
            if atoms.len() > 1 {
                quote!(#c * (#inner))
            } else {
                quote!(#c * #inner)
            }
        };
        out = match (gi, gneg) {
            (0, false) => term,
            (0, true) => quote!(-#term),
            (_, false) => quote!(#out + #term),
            (_, true) => quote!(#out - #term),
        };
    }
    out
}

/// Names of the definitions that the outputs depend on.
fn live_defs(k: &Kernel) -> BTreeSet<Var> {
    let mut live: BTreeSet<Var> = BTreeSet::new();
    let mark = |p: &Poly, live: &mut BTreeSet<Var>| {
        for m in p.terms.keys() {
            for &(v, _) in &m.0 {
                live.insert(v);
            }
        }
    };
    for (_, p) in &k.outputs {
        mark(p, &mut live);
    }
    for d in k.defs.iter().rev() {
        if live.contains(&d.var) {
            mark(&d.poly, &mut live);
        }
    }
    live
}

/// Emits one kernel.
pub fn emit(k: &Kernel) -> Emitted {
    let live = live_defs(k);
    let expanded = k.expanded_outputs();
    let (naive_terms, naive) = naive_ops(&expanded);

    let mut e = Emitter {
        k,
        monos: BTreeMap::new(),
        taken: BTreeSet::new(),
        lines: Vec::new(),
        ops: OpCount::default(),
    };
    for n in &k.ring.names {
        e.taken.insert(n.clone());
    }
    for i in &k.inputs {
        e.taken.insert(i.name.clone());
    }
    // Bind the inputs that are used.
    for input in &k.inputs {
        let arr = ident(&input.name);
        for (idx, &v) in input.vars.iter().enumerate() {
            e.monos.insert(Mono::var(v), e.name_of(v).to_string());
            if input.kind == InputKind::Array && live.contains(&v) {
                let id = ident(e.name_of(v));
                let ix = Literal::usize_unsuffixed(idx);
                e.lines.push(quote!(let #id = #arr[#ix];));
            }
        }
    }
    // Definitions in groups of mutually independent consecutive definitions.
    let defs: Vec<_> = k.defs.iter().filter(|d| live.contains(&d.var)).collect();
    let mut i = 0;
    while i < defs.len() {
        let mut group_vars: BTreeSet<Var> = BTreeSet::new();
        let mut j = i;
        while j < defs.len() && defs[j].poly.all_vars(|v| !group_vars.contains(&v)) {
            group_vars.insert(defs[j].var);
            j += 1;
        }
        let items: Vec<(String, Poly)> = defs[i..j]
            .iter()
            .map(|d| (e.name_of(d.var).to_string(), d.poly.clone()))
            .collect();
        for (d, name) in defs[i..j].iter().zip(e.emit_group(&items, true)) {
            e.monos.insert(Mono::var(d.var), name);
        }
        i = j;
    }
    let out_names = e.emit_group(&k.outputs, false);

    // Function signature.
    let fname = ident(&k.name);
    let params: Vec<TokenStream> = k
        .inputs
        .iter()
        .map(|i| {
            let n = ident(&i.name);
            match i.kind {
                InputKind::Array => {
                    let len = Literal::usize_unsuffixed(i.vars.len());
                    quote!(#n: &[f64; #len])
                }
                InputKind::Scalar => quote!(#n: f64),
            }
        })
        .collect();
    let out_ids: Vec<Ident> = out_names.iter().map(|n| ident(n)).collect();
    let (ret_ty, ret_expr) = if k.scalar_output {
        assert_eq!(out_ids.len(), 1, "scalar kernel with several outputs");
        let o = &out_ids[0];
        (quote!(f64), quote!(#o))
    } else {
        let n = Literal::usize_unsuffixed(out_ids.len());
        (quote!([f64; #n]), quote!([#(#out_ids),*]))
    };

    // Documentation.
    let mut doc: Vec<String> = Vec::new();
    for (pi, para) in k.doc.iter().enumerate() {
        if pi > 0 {
            doc.push(String::new());
        }
        doc.extend(para.lines().map(str::to_string));
    }
    doc.push(String::new());
    doc.push("# Inputs".to_string());
    for i in &k.inputs {
        doc.push(format!("- `{}`: {}", i.name, i.doc));
    }
    doc.push(String::new());
    doc.push("# Output".to_string());
    doc.extend(k.output_doc.lines().map(str::to_string));
    doc.push(String::new());
    doc.push("# Operation count".to_string());
    doc.push(format!(
        "{} mul + {} add after common-subexpression elimination; the fully expanded \
         outputs have {} terms and cost {} mul + {} add evaluated term by term.",
        e.ops.mul, e.ops.add, naive_terms, naive.mul, naive.add
    ));
    let doc_attrs: Vec<TokenStream> = doc
        .iter()
        .map(|l| {
            let s = if l.is_empty() {
                String::new()
            } else {
                format!(" {l}")
            };
            quote!(#[doc = #s])
        })
        .collect();

    let body = &e.lines;
    let ops_name = ident(&format!("{}_OPS", k.name.to_uppercase()));
    let (m, a, nm, na, nt) = (
        Literal::usize_unsuffixed(e.ops.mul),
        Literal::usize_unsuffixed(e.ops.add),
        Literal::usize_unsuffixed(naive.mul),
        Literal::usize_unsuffixed(naive.add),
        Literal::usize_unsuffixed(naive_terms),
    );
    let name_str = &k.name;
    let ops_doc = format!(" Operation counts of [`{}`].", k.name);
    let tables: Vec<TokenStream> = k
        .tables
        .iter()
        .map(|t| {
            let n = ident(&t.name);
            let ty: TokenStream = t.elem_ty.parse().expect("table type");
            let len = Literal::usize_unsuffixed(t.elems.len());
            let elems: Vec<TokenStream> = t
                .elems
                .iter()
                .map(|x| x.parse().expect("table element"))
                .collect();
            let docs: Vec<TokenStream> = t
                .doc
                .lines()
                .map(|l| {
                    let s = format!(" {l}");
                    quote!(#[doc = #s])
                })
                .collect();
            quote! {
                #(#docs)*
                pub const #n: [#ty; #len] = [#(#elems),*];
            }
        })
        .collect();

    let file = quote! {
        #(#doc_attrs)*
        #[inline]
        #[must_use]
        pub fn #fname(#(#params),*) -> #ret_ty {
            #(#body)*
            #ret_expr
        }

        #[doc = #ops_doc]
        pub const #ops_name: KernelOps = KernelOps {
            name: #name_str,
            mul: #m,
            add: #a,
            naive_mul: #nm,
            naive_add: #na,
            naive_terms: #nt,
        };

        #(#tables)*
    };
    let parsed = syn::parse2::<syn::File>(file).expect("emitted tokens parse as a Rust file");
    let pretty = prettyplease::unparse(&parsed);
    let banner = format!(
        "// @generated by eopnp-codegen from {def}, kernel `{name}`. Do not edit.\n\
         // Committed copy: generated/{name}.rs; refresh it with `cargo run -p eopnp-codegen -- emit generated`.\n\
         // Ops after CSE: {m} mul, {a} add. Naive expansion: {t} terms, {nm} mul, {na} add.\n\n",
        def = k.definition,
        name = k.name,
        m = e.ops.mul,
        a = e.ops.add,
        t = naive_terms,
        nm = naive.mul,
        na = naive.add,
    );
    Emitted {
        source: banner + &pretty,
        ops: e.ops,
        naive,
        naive_terms,
    }
}
