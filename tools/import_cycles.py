#!/usr/bin/env python3
"""Import circles between the files of a Rust crate.

Usage: tools/import_cycles.py CRATE/src [--max N]

Builds the graph "file A uses a module of file B" from the paths in the crate's source
(`crate::x`, `crate::x::y::z`, `super::x`, `super::*`, `self::x`, in `use` items and inline
paths, and `use child::x` into the file's own child modules; comments and string literals are
ignored; inline modules such as `#[cfg(test)] mod tests { use super::*; }` are read as the
modules they are, so that one names its own file) and prints
its strongly connected components of more than one file, largest first. With `--max N` the
exit status is 1 when a component has more than N files (for CI).

A path is resolved to the deepest module file that exists: `crate::a::b::C` is
`src/a/b.rs` (or `src/a/b/mod.rs`) when that exists, else `src/a.rs` (or `src/a/mod.rs`).
`main.rs` and files under `bin/` are crate roots of their own and are skipped, as is
`lib.rs` (it only declares the modules). Method calls on a type whose `impl` block is in
another file are not imports and are not seen.
"""

import argparse
import os
import re
import sys


def strip_comments_and_strings(text):
    """Removes comments, string and char literals (keeps line structure roughly)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith("/*", i):
                    depth, i = depth + 1, i + 2
                elif text.startswith("*/", i):
                    depth, i = depth - 1, i + 2
                else:
                    i += 1
        elif c == "r" and re.match(r'r#*"', text[i:i + 10]) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'r(#*)"', text[i:])
            hashes = m.group(1)
            end = text.find('"' + hashes, i + len(m.group(0)))
            i = n if end < 0 else end + 1 + len(hashes)
            out.append('""')
        elif c == '"':
            i += 1
            while i < n and text[i] != '"':
                i += 2 if text[i] == "\\" else 1
            i += 1
            out.append('""')
        elif c == "'" and re.match(r"'(\\.|[^\\'])'", text[i:i + 4]):
            m = re.match(r"'(\\.|[^\\'])'", text[i:])
            i += len(m.group(0))
            out.append("' '")
        else:
            out.append(c)
            i += 1
    return "".join(out)


def module_path_of(src, path):
    """Module path (list of names) of a file relative to src."""
    rel = os.path.relpath(path, src)
    parts = rel[:-3].split(os.sep)
    if parts[-1] == "mod":
        parts = parts[:-1]
    return parts


def expand_use_tree(prefix, tree):
    """Expands `a::{b, c::{d, e}}` into full paths (lists of names)."""
    tree = tree.strip()
    brace = tree.find("{")
    if brace < 0:
        parts = [p.strip() for p in tree.split("::") if p.strip()]
        parts = [p.split(" as ")[0].strip() for p in parts]
        return [prefix + parts]
    head = [p.strip() for p in tree[:brace].split("::") if p.strip()]
    inner = tree[brace + 1:tree.rfind("}")]
    items, depth, cur = [], 0, ""
    for ch in inner:
        if ch == "," and depth == 0:
            items.append(cur)
            cur = ""
            continue
        depth += ch == "{"
        depth -= ch == "}"
        cur += ch
    items.append(cur)
    paths = []
    for item in items:
        if item.strip():
            paths.extend(expand_use_tree(prefix + head, item))
    return paths


def inline_modules(text):
    """(start, end, name) of every inline `mod name { ... }` block, outermost first."""
    blocks = []
    for m in re.finditer(r"\bmod\s+([A-Za-z_][A-Za-z0-9_]*)\s*\{", text):
        depth, i = 1, m.end()
        while i < len(text) and depth:
            depth += text[i] == "{"
            depth -= text[i] == "}"
            i += 1
        blocks.append((m.start(), i, m.group(1)))
    return blocks


def inline_prefix(blocks, position):
    """The inline modules around `position`, outermost first."""
    return [name for start, end, name in blocks if start < position < end]


def referenced_paths(text):
    """Every path of the file's `use` items and every inline path starting with crate / super /
    self, each with the inline modules it stands in (a `super::*` in a file's `mod tests { }`
    names the file itself)."""
    blocks = inline_modules(text)
    paths = []
    for m in re.finditer(r"\buse\s+([^;]+);", text):
        prefix = inline_prefix(blocks, m.start())
        paths.extend((prefix, p) for p in expand_use_tree([], m.group(1)))
    # Inline paths (also catches the `use` ones again, harmlessly).
    for m in re.finditer(r"\b((?:crate|super|self)(?:\s*::\s*[A-Za-z_*][A-Za-z0-9_]*)+)", text):
        prefix = inline_prefix(blocks, m.start())
        paths.append((prefix, [p.strip() for p in m.group(1).split("::")]))
    return paths


def resolve(src, files_by_module, own_module, path):
    """The file that `path`, used in the file of module `own_module`, points into: `crate::`,
    `super::` and `self::` paths, and relative paths into the file's own child modules
    (`use child::Item`, as a module root declaring `mod child;` writes them)."""
    if not path:
        return None
    if path[0] == "crate":
        base, rest = [], path[1:]
    elif path[0] in ("super", "self"):
        base = list(own_module)
        rest = list(path)
        while rest and rest[0] in ("super", "self"):
            if rest[0] == "super" and base:
                base = base[:-1]
            rest = rest[1:]
    elif tuple(list(own_module) + [path[0]]) in files_by_module:
        base, rest = list(own_module), list(path)
    else:
        return None
    best = None
    for k in range(len(rest) + 1):
        key = tuple(base + rest[:k])
        if key in files_by_module:
            best = files_by_module[key]
    return best


def tarjan(nodes, edges):
    index, low, on_stack, stack, sccs = {}, {}, set(), [], []
    counter = [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            scc = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                scc.append(w)
                if w == v:
                    break
            sccs.append(sorted(scc))

    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return sccs


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("src", help="the crate's src folder")
    ap.add_argument("--max", type=int, help="fail when a circle has more files than this")
    ap.add_argument("--edges", action="store_true", help="also print the edges inside circles")
    args = ap.parse_args()
    src = os.path.abspath(args.src)
    files = []
    for root, _, names in os.walk(src):
        for name in names:
            if name.endswith(".rs"):
                files.append(os.path.join(root, name))
    files_by_module = {}
    for f in files:
        rel = os.path.relpath(f, src)
        if rel in ("main.rs", "lib.rs") or rel.startswith("bin" + os.sep):
            continue
        files_by_module[tuple(module_path_of(src, f))] = rel
    edges = {}
    for module, rel in files_by_module.items():
        with open(os.path.join(src, rel), encoding="utf-8") as fh:
            text = strip_comments_and_strings(fh.read())
        for prefix, p in referenced_paths(text):
            target = resolve(src, files_by_module, list(module) + prefix, p)
            if target and target != rel:
                edges.setdefault(rel, set()).add(target)
    nodes = set(files_by_module.values())
    sccs = [s for s in tarjan(nodes, edges) if len(s) > 1]
    sccs.sort(key=lambda s: (-len(s), s))
    n_edges = sum(len(v) for v in edges.values())
    print(f"{len(nodes)} files, {n_edges} file-to-file uses")
    if not sccs:
        print("no import circle")
    for s in sccs:
        print(f"circle of {len(s)} files: {' '.join(s)}")
        if args.edges:
            members = set(s)
            for a in s:
                inside = sorted(b for b in edges.get(a, ()) if b in members)
                print(f"    {a} -> {' '.join(inside)}")
    largest = max((len(s) for s in sccs), default=1)
    print(f"largest circle: {largest if sccs else 0} files")
    if args.max is not None and sccs and largest > args.max:
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
