//! The module graph of every crate of the workspace has no cycle, and the pipeline's stages are
//! called only by its driver.
//!
//! Each production file under a crate's `src/` (test files — `tests.rs` and what follows a
//! `#[cfg(test)]` module declaration — are left out) is a module; an edge `a -> b` is any path
//! `crate::b...`, `super::...` or `self::...` in a `use` item or in the code (comments and doc
//! comments are skipped) that resolves into module `b`, where `b` is not `a` itself, an ancestor
//! of `a` or a descendant of `a`. A parent's `mod x;` declarations and `pub use` re-exports of
//! its children are the tree, not edges. The graph is checked as it is and collapsed to the
//! crate's top-level modules; the test fails with the cycle it finds.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Module path (`["pipeline", "frame"]`) of a source file relative to `src/`.
fn module_of(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().unwrap();
    let stem = last.trim_end_matches(".rs");
    if stem != "mod" && stem != "lib" && stem != "main" {
        parts.push(stem.to_string());
    }
    parts
}

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The production code of a file: without comments, and without a trailing test module.
fn production_code(text: &str) -> String {
    let mut out = String::new();
    let mut lines = text.lines().peekable();
    while let Some(l) = lines.next() {
        let t = l.trim_start();
        if t.starts_with("#[cfg(test)]") {
            // A test-only item: skip it (a `mod tests;` line, or a block to its closing brace
            // at the same indentation).
            // Further attributes (`#[path = ...]`) belong to the same item.
            let Some(mut next) = lines.next() else { break };
            while next.trim_start().starts_with("#[") {
                let Some(n) = lines.next() else { break };
                next = n;
            }
            if next.trim_end().ends_with(';') {
                continue;
            }
            let indent = next.len() - next.trim_start().len();
            for l in lines.by_ref() {
                if l.len() - l.trim_start().len() == indent && l.trim_start().starts_with('}') {
                    break;
                }
            }
            continue;
        }
        if t.starts_with("//") {
            continue;
        }
        let code = match l.find("//") {
            Some(i) if !l[..i].contains('"') => &l[..i],
            _ => l,
        };
        out.push_str(code);
        out.push('\n');
    }
    out
}

/// Resolves `crate::a::b`, `super::a`, `self::a` (as written in `module`) to the longest known
/// module prefix.
fn resolve(
    module: &[String],
    is_mod_rs: bool,
    path: &[&str],
    known: &BTreeSet<Vec<String>>,
    root_exports: &BTreeMap<String, Vec<String>>,
) -> Option<Vec<String>> {
    let mut base: Vec<String> = match path.first()? {
        // A name the crate root re-exports (`crate::Solver`) is an edge to where it lives.
        &"crate" if path.len() >= 2 && root_exports.contains_key(path[1]) => {
            return Some(root_exports[path[1]].clone());
        }
        &"crate" => Vec::new(),
        &"self" | &"super" => {
            // `self` of a `foo.rs` or `foo/mod.rs` file is the module itself.
            let mut b = module.to_vec();
            let _ = is_mod_rs;
            for seg in path.iter().take_while(|s| **s == "super" || **s == "self") {
                if *seg == "super" {
                    b.pop()?;
                }
            }
            b
        }
        _ => return None,
    };
    let rest = path
        .iter()
        .skip_while(|s| matches!(**s, "crate" | "self" | "super"));
    let mut best = base.clone();
    for seg in rest {
        base.push(seg.to_string());
        if known.contains(&base) {
            best = base.clone();
        } else {
            break;
        }
    }
    Some(best)
}

/// Every `crate::`/`super::`/`self::` path in `code`, with `use` groups expanded one level
/// (`use crate::a::{b, c::d}` gives `crate::a::b` and `crate::a::c::d`).
fn paths(code: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let bytes: Vec<char> = code.chars().collect();
    let mut i = 0;
    while i < bytes.len() {
        let starts = ["crate::", "super::", "self::"]
            .iter()
            .find(|p| code_at(&bytes, i).starts_with(**p));
        let boundary = i == 0 || !(bytes[i - 1].is_alphanumeric() || bytes[i - 1] == '_');
        if let (Some(_), true) = (starts, boundary) {
            let mut j = i;
            let mut segs = Vec::new();
            let mut cur = String::new();
            while j < bytes.len() {
                let c = bytes[j];
                if c.is_alphanumeric() || c == '_' {
                    cur.push(c);
                    j += 1;
                } else if c == ':' && j + 1 < bytes.len() && bytes[j + 1] == ':' {
                    segs.push(std::mem::take(&mut cur));
                    j += 2;
                } else {
                    break;
                }
            }
            if !cur.is_empty() {
                segs.push(cur);
            }
            if j < bytes.len() && bytes[j] == '{' {
                // A use group: each member, one level deep.
                let end = (j..bytes.len())
                    .find(|&k| bytes[k] == '}')
                    .unwrap_or(bytes.len());
                let inner: String = bytes[j + 1..end].iter().collect();
                for member in inner.split(',') {
                    let member = member.trim();
                    let mut s = segs.clone();
                    for m in member.split("::") {
                        let m = m.trim().trim_start_matches('{');
                        if !m.is_empty() && m != "self" {
                            s.push(m.split_whitespace().next().unwrap_or("").to_string());
                        }
                    }
                    out.push(s);
                }
                i = end;
            } else {
                out.push(segs);
                i = j;
            }
        } else {
            i += 1;
        }
    }
    out
}

fn code_at(s: &[char], i: usize) -> String {
    s[i..(i + 8).min(s.len())].iter().collect()
}

/// The module graph of the crate whose sources are in `src`.
fn graph(src: &Path) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let mut fs = Vec::new();
    files(src, &mut fs);
    let mut modules = BTreeMap::new();
    for f in &fs {
        let rel = f.strip_prefix(src).unwrap();
        let name = rel.file_name().unwrap().to_string_lossy().into_owned();
        if name == "tests.rs" || name == "test_data.rs" || rel.starts_with("bin") {
            continue;
        }
        if name == "main.rs" && rel.parent() == Some(Path::new("")) {
            continue; // the binary is its own crate
        }
        modules.insert(module_of(rel), (f.clone(), name == "mod.rs"));
    }
    let known: BTreeSet<Vec<String>> = modules.keys().cloned().collect();
    // Names re-exported by the crate root (`pub use a::b::{X, Y};` in lib.rs): `crate::X`
    // resolves to the module `a::b` (or the longest known prefix of it).
    let mut root_exports = BTreeMap::new();
    if let Some((root_file, _)) = modules.get(&Vec::new()) {
        let code = production_code(&std::fs::read_to_string(root_file).unwrap());
        for line in code.lines() {
            let Some(rest) = line.trim_start().strip_prefix("pub use ") else {
                continue;
            };
            for p in paths(&format!("crate::{rest}")) {
                let Some((name, prefix)) = p.split_last() else {
                    continue;
                };
                let segs: Vec<&str> = prefix.iter().map(String::as_str).collect();
                if let Some(target) = resolve(&[], false, &segs, &known, &BTreeMap::new()) {
                    if !target.is_empty() {
                        root_exports.insert(name.clone(), target);
                    }
                }
            }
        }
    }
    let mut g: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (m, (f, is_mod_rs)) in &modules {
        let code = production_code(&std::fs::read_to_string(f).unwrap());
        let edges = g.entry(m.clone()).or_default();
        for line in code.lines() {
            // The tree itself: `mod x;` and re-exports of descendants are not edges.
            let t = line.trim_start();
            if t.starts_with("mod ")
                || t.starts_with("pub mod ")
                || t.starts_with("pub(crate) mod ")
            {
                continue;
            }
            for p in paths(line) {
                let segs: Vec<&str> = p.iter().map(String::as_str).collect();
                let Some(target) = resolve(m, *is_mod_rs, &segs, &known, &root_exports) else {
                    continue;
                };
                let related = target.starts_with(m) || m.starts_with(&target);
                if !related {
                    edges.insert(target);
                }
            }
        }
    }
    g
}

/// A cycle of the graph, if there is one.
fn find_cycle(g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Option<Vec<Vec<String>>> {
    #[derive(Clone, Copy, PartialEq)]
    enum State {
        New,
        Open,
        Done,
    }
    fn visit(
        n: &Vec<String>,
        g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        st: &mut BTreeMap<Vec<String>, State>,
        stack: &mut Vec<Vec<String>>,
    ) -> Option<Vec<Vec<String>>> {
        st.insert(n.clone(), State::Open);
        stack.push(n.clone());
        for m in g.get(n).into_iter().flatten() {
            match st.get(m).copied().unwrap_or(State::New) {
                State::Open => {
                    let k = stack.iter().position(|x| x == m).unwrap();
                    let mut c = stack[k..].to_vec();
                    c.push(m.clone());
                    return Some(c);
                }
                State::New => {
                    if let Some(c) = visit(m, g, st, stack) {
                        return Some(c);
                    }
                }
                State::Done => {}
            }
        }
        stack.pop();
        st.insert(n.clone(), State::Done);
        None
    }
    let mut st = BTreeMap::new();
    for n in g.keys() {
        if st.get(n).copied().unwrap_or(State::New) == State::New {
            if let Some(c) = visit(n, g, &mut st, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

fn show(c: &[Vec<String>]) -> String {
    c.iter()
        .map(|m| {
            if m.is_empty() {
                "crate".to_string()
            } else {
                m.join("::")
            }
        })
        .collect::<Vec<_>>()
        .join(" -> ")
}

#[test]
fn no_module_cycle_in_any_crate() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for krate in [
        "src",
        "cli/src",
        "codegen/src",
        "verify/src",
        "compare/src",
        "testkit/src",
        "capi/src",
        // The Python package's extension module (its own workspace, scanned all the same).
        "python/src",
    ] {
        let g = graph(&root.join(krate));
        assert!(g.len() > 1 || krate != "src", "{krate}: no modules found");
        if let Some(c) = find_cycle(&g) {
            panic!("{krate}: module cycle {}", show(&c));
        }
        // The same at the level of the crate's top modules (a module and everything in it):
        // `a::x -> b::y` and `b::z -> a` is a cycle between `a` and `b`.
        let mut top: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
        for (from, tos) in &g {
            let f: Vec<String> = from.iter().take(1).cloned().collect();
            let e = top.entry(f.clone()).or_default();
            for to in tos {
                let t: Vec<String> = to.iter().take(1).cloned().collect();
                if t != f && !t.is_empty() && !f.is_empty() {
                    e.insert(t);
                }
            }
        }
        if let Some(c) = find_cycle(&top) {
            panic!("{krate}: cycle between top-level modules {}", show(&c));
        }
    }
}

#[test]
fn stages_are_called_only_by_the_driver() {
    // Within the pipeline, a stage may use the types and helpers of the stages before it
    // (data flows down), never one after it, and never the driver (`pipeline/mod.rs`), which
    // is the only caller of the stages.
    let order = [
        "moments",
        "frame",
        "nullspace",
        "planar",
        "search",
        "newton",
        "certificate",
        "select",
        "refine",
        "options",
        "refine_pixels",
        "refine_rig",
        "output",
        "bench_hooks",
    ];
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let g = graph(&root.join("src"));
    let rank = |m: &Vec<String>| -> Option<usize> {
        (m.len() == 2 && m[0] == "pipeline")
            .then(|| order.iter().position(|s| *s == m[1]))
            .flatten()
    };
    for (from, tos) in &g {
        let Some(rf) = rank(from) else { continue };
        for to in tos {
            if to.len() == 1 && to[0] == "pipeline" {
                panic!("stage {} imports the driver", from.join("::"));
            }
            if let Some(rt) = rank(to) {
                assert!(
                    rt < rf,
                    "stage {} uses the later stage {}",
                    from.join("::"),
                    to.join("::")
                );
            }
        }
    }
}

/// The layers of the library, top to bottom, as the contributor guide's table lists them (the
/// rows between `<!-- layers:begin -->` and `<!-- layers:end -->` in CONTRIBUTING.md: the first
/// column names the layer, the second its files, `src/x.rs` or `src/x/`). Each layer may use the
/// layers above it (and `src/error.rs`, used by all), never one below: the test fails with the
/// edge that breaks the table, and with a top-level module the table does not place.
#[test]
fn each_layer_uses_only_the_layers_above_it() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let guide = std::fs::read_to_string(root.join("CONTRIBUTING.md")).unwrap();
    let table = guide
        .split("<!-- layers:begin -->")
        .nth(1)
        .and_then(|t| t.split("<!-- layers:end -->").next())
        .expect("CONTRIBUTING.md: no <!-- layers:begin --> ... <!-- layers:end --> table");
    // Layer index of each top-level module, from the rows' second column.
    let mut layer_of: BTreeMap<String, (usize, String)> = BTreeMap::new();
    let rows = table
        .lines()
        .filter(|l| l.starts_with('|') && !l.starts_with("|---"))
        .skip(1);
    for (k, row) in rows.enumerate() {
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let (name, files) = (cells[1], cells[2]);
        for f in files.split(',') {
            let f = f.trim().trim_matches('`');
            let module = f
                .strip_prefix("src/")
                .unwrap_or_else(|| panic!("layer {name}: {f} is not under src/"))
                .trim_end_matches('/')
                .trim_end_matches(".rs");
            assert!(root.join(f).exists(), "layer {name}: {f} does not exist");
            layer_of.insert(module.to_string(), (k, name.to_string()));
        }
    }
    assert!(
        layer_of.len() >= 8,
        "the layers table lists {} modules",
        layer_of.len()
    );
    let g = graph(&root.join("src"));
    let top = |m: &Vec<String>| m.first().cloned();
    for (from, tos) in &g {
        let Some(f) = top(from) else { continue }; // the crate root
        if f == "error" {
            continue;
        }
        let (lf, nf) = layer_of
            .get(&f)
            .unwrap_or_else(|| panic!("src/{f}: not placed in CONTRIBUTING.md's layers table"));
        for to in tos {
            let Some(t) = top(to) else { continue };
            if t == f || t == "error" {
                continue;
            }
            let (lt, nt) = layer_of
                .get(&t)
                .unwrap_or_else(|| panic!("src/{t}: not placed in CONTRIBUTING.md's layers table"));
            assert!(
                lt <= lf,
                "{} ({nf}) uses {} ({nt}), a layer below it in CONTRIBUTING.md's table",
                from.join("::"),
                to.join("::")
            );
        }
    }
}
