#!/usr/bin/env python3
"""The public API of a crate of this workspace, one line per item, from rustdoc's JSON.

    python3 scripts/public_api.py [-p CRATE] [--features all|F,G] [--count]
    python3 scripts/public_api.py --check CONTRIBUTING.md

Lists every item a user of the crate can name (with every feature on, unless --features says
otherwise): modules, structs and their public fields,
enums and their variants, traits and their items, functions, inherent methods and associated
constants, constants, statics, type aliases, macros, and re-exports of other crates' items
(as one line each: `pub use eopnp::ArrayVec = arrayvec::ArrayVec`). Trait implementations
(`impl Clone for ...`) are not listed. `#[doc(hidden)]` items are listed, marked `(hidden)`:
they are public all the same.

The JSON comes from `cargo rustdoc -- --output-format json`, an unstable rustdoc flag:
the script sets RUSTC_BOOTSTRAP=1 for that one command, so that the stable toolchain
produces it (into target/public-api/, outside the normal build's directories).

`--check FILE` compares the list with the one between the markers
`<!-- public-api:begin -->` and `<!-- public-api:end -->` in FILE (lines starting with
`- `, each naming an item as `` `path` ``, then its description) and exits with status 1,
printing the difference, if an item is missing from the file or listed there but gone.
"""

import argparse
import json
import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def rustdoc_json(crate: str, features: str) -> dict:
    target = ROOT / "target" / "public-api"
    env = dict(os.environ, RUSTC_BOOTSTRAP="1", CARGO_TARGET_DIR=str(target))
    cmd = ["cargo", "rustdoc", "--quiet", "-p", crate, "--lib"]
    cmd += ["--all-features"] if features == "all" else ["--features", features] if features else []
    cmd += ["--", "-Z", "unstable-options", "--output-format", "json", "--document-hidden-items"]
    subprocess.run(cmd, check=True, cwd=ROOT, env=env)
    path = target / "doc" / (crate.replace("-", "_") + ".json")
    return json.loads(path.read_text())


def is_hidden(item: dict) -> bool:
    for a in item.get("attrs", []):
        text = a if isinstance(a, str) else json.dumps(a)
        if "doc(hidden)" in text.replace(" ", "") or '"hidden"' in text:
            return True
    return False


def summary(docs: str) -> str:
    """The first sentence of an item's documentation, links reduced to their text."""
    para = docs.strip().split("\n\n")[0].replace("\n", " ")
    para = re.sub(r"\[`([^`]*)`\]\([^)]*\)", r"`\1`", para)
    para = re.sub(r"\[`([^`]*)`\]", r"`\1`", para)
    para = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", para)
    m = re.match(r"(.*?\.)(\s|$)", para)
    first = m.group(1) if m else para
    return first.strip()


docs = {}


def walk(doc: dict) -> list:
    index = doc["index"]
    paths = doc.get("paths", {})
    out = []
    seen = set()

    def add(kind, path, item=None, hidden=False):
        mark = " (hidden)" if hidden or (item is not None and is_hidden(item)) else ""
        out.append(f"{kind} {path}{mark}")
        docs[f"{kind} {path}{mark}"] = summary((item or {}).get("docs") or "")

    def impls_of(item_id, owner_path, hidden):
        item = index[str(item_id)]
        inner = next(iter(item["inner"].values()))
        for impl_id in inner.get("impls", []):
            impl = index.get(str(impl_id))
            if impl is None:
                continue
            body = impl["inner"]["impl"]
            if body.get("trait") is not None or body.get("is_synthetic") or body.get("blanket_impl"):
                continue
            for sub in body["items"]:
                it = index.get(str(sub))
                if it is None or it["visibility"] != "public":
                    continue
                kind = next(iter(it["inner"]))
                word = {"function": "fn", "assoc_const": "const", "assoc_type": "type"}.get(kind, kind)
                add(word, f"{owner_path}::{it['name']}", it, hidden)

    def members(item_ids, path, hidden, public_only=True):
        """The items of a module (its `pub use` re-exports and globs expanded) under `path`."""
        for sub in item_ids:
            it = index.get(str(sub))
            if it is None or (public_only and it["visibility"] != "public"):
                continue
            sk, si = next(iter(it["inner"].items()))
            if sk != "use":
                visit(sub, f"{path}::{it['name']}", hidden)
            elif not si.get("is_glob"):
                visit(si.get("id"), f"{path}::{si['name']}", hidden or is_hidden(it))
            else:
                target = index.get(str(si.get("id")))
                if target is None or "module" not in target["inner"]:
                    add("pub use", f"{path}::* = {si.get('source')}::*", it, hidden)
                else:
                    # A glob re-exports the public items of its module, private or not.
                    members(target["inner"]["module"]["items"], path, hidden or is_hidden(it))

    def visit(item_id, path, hidden=False):
        key = (str(item_id), path)
        if key in seen:
            return
        seen.add(key)
        item = index.get(str(item_id))
        if item is None:
            # An item of another crate, re-exported.
            src = paths.get(str(item_id), {}).get("path")
            add("pub use", f"{path} = {'::'.join(src) if src else '?'}", None, hidden)
            return
        hidden = hidden or is_hidden(item)
        kind, inner = next(iter(item["inner"].items()))
        if kind == "module":
            if not inner.get("is_crate"):
                add("mod", path, item, hidden)
            members(inner["items"], path, hidden)
        elif kind == "struct":
            add("struct", path, item, hidden)
            k = inner["kind"]
            fields = []
            if isinstance(k, dict) and "plain" in k:
                fields = k["plain"]["fields"]
            elif isinstance(k, dict) and "tuple" in k:
                fields = [f for f in k["tuple"] if f is not None]
            for f in fields:
                fi = index.get(str(f))
                if fi is not None and fi["visibility"] == "public":
                    add("field", f"{path}::{fi['name']}", fi, hidden)
            impls_of(item_id, path, hidden)
        elif kind == "enum":
            add("enum", path, item, hidden)
            for v in inner["variants"]:
                vi = index[str(v)]
                add("variant", f"{path}::{vi['name']}", vi, hidden)
                vk = vi["inner"]["variant"]["kind"]
                if isinstance(vk, dict) and "struct" in vk:
                    for f in vk["struct"]["fields"]:
                        fi = index.get(str(f))
                        if fi is not None:
                            add("field", f"{path}::{vi['name']}::{fi['name']}", fi, hidden)
            impls_of(item_id, path, hidden)
        elif kind == "trait":
            add("trait", path, item, hidden)
            for sub in inner["items"]:
                it = index.get(str(sub))
                if it is not None:
                    add("trait item", f"{path}::{it['name']}", it, hidden)
        elif kind == "function":
            add("fn", path, item, hidden)
        elif kind in ("constant", "static", "type_alias", "macro", "union"):
            word = {"constant": "const", "type_alias": "type"}.get(kind, kind)
            add(word, path, item, hidden)
            if kind in ("type_alias",):
                pass
        else:
            add(kind, path, item, hidden)

    visit(doc["root"], doc["index"][str(doc["root"])]["name"])
    return sorted(set(out), key=lambda s: (s.split(" ", 1)[1] if " " in s else s, s))


def listed(file: Path) -> list:
    text = file.read_text()
    m = re.search(r"<!-- public-api:begin -->(.*?)<!-- public-api:end -->", text, re.S)
    if not m:
        sys.exit(f"{file}: no <!-- public-api:begin --> ... <!-- public-api:end --> block")
    items = []
    for line in m.group(1).splitlines():
        m2 = re.match(r"\s*- `([^`]+)`", line)
        if m2:
            items.append(m2.group(1))
    return items


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-p", "--package", default="eopnp")
    ap.add_argument("--features", default="all", help="'all' (default), or a list for --features")
    ap.add_argument("--count", action="store_true", help="print the counts by kind only")
    ap.add_argument("--markdown", action="store_true",
                    help="a Markdown list: each item with the first sentence of its documentation")
    ap.add_argument("--check", type=Path, help="compare with the list in this Markdown file")
    args = ap.parse_args()
    items = walk(rustdoc_json(args.package, args.features))
    if args.check:
        have = {i for i in items}
        # The file names items by path with their kind: `fn eopnp::solve`.
        want = set(listed(args.check))
        missing = sorted(have - want)
        extra = sorted(want - have)
        for m in missing:
            print(f"not in {args.check}: {m}")
        for e in extra:
            print(f"in {args.check} but not public: {e}")
        if missing or extra:
            sys.exit(1)
        print(f"{args.check}: the {len(have)} public items of {args.package} listed")
        return
    if args.count:
        counts = {}
        for i in items:
            k = i.split(" ")[0] if not i.startswith("pub use") else "pub use"
            if i.startswith("trait item"):
                k = "trait item"
            counts[k] = counts.get(k, 0) + 1
        for k in sorted(counts):
            print(f"{k}: {counts[k]}")
        print(f"total: {len(items)}")
        return
    if args.markdown:
        for i in items:
            d = docs.get(i, "")
            print(f"- `{i}`" + (f": {d}" if d else ""))
        return
    print("\n".join(items))


if __name__ == "__main__":
    main()
