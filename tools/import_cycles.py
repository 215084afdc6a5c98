#!/usr/bin/env python3
"""Import circles between the files of a Rust crate.

Usage: tools/import_cycles.py CRATE/src [--max N]

Builds the graph "file A uses a module of file B" from the paths in the crate's source
(`crate::x`, `crate::x::y::z`, `super::x`, `self::x`, in `use` items and inline paths;
comments and string literals are ignored; `#[cfg(test)]` modules are included) and prints
its strongly connected components of more than one file, largest first. With `--max N` the
exit status is 1 when a component has more than N files (for CI).

A path is resolved to the deepest module file that exists: `crate::a::b::C` is
`src/a/b.rs` (or `src/a/b/mod.rs`) when that exists, else `src/a.rs` (or `src/a/mod.rs`).
`main.rs` and files under `bin/` are crate roots of their own and are skipped, as is
`lib.rs` (it only declares the modules). Inline `mod name { ... }` blocks are not tracked:
their paths count as the file's (a `super::` inside one reads one level too high, which for a
`#[cfg(test)] mod tests { use super::*; }` only drops a use of the file itself). Method calls
on a type whose `impl` block is in another file are not imports and are not seen.
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


def referenced_paths(text):
    """Every path starting with crate / super / self in the file."""
    paths = []
    for m in re.finditer(r"\buse\s+([^;]+);", text):
        tree = m.group(1)
        if tree.split("::")[0].strip() in ("crate", "super", "self"):
            paths.extend(expand_use_tree([], tree))
    # Inline paths (also catches the `use` ones again, harmlessly).
    for m in re.finditer(r"\b((?:crate|super|self)(?:\s*::\s*[A-Za-z_][A-Za-z0-9_]*)+)", text):
        paths.append([p.strip() for p in m.group(1).split("::")])
    return paths


def resolve(src, files_by_module, own_module, path):
    """The file that `path`, used in the file of module `own_module`, points into."""
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
        for p in referenced_paths(text):
            target = resolve(src, files_by_module, list(module), p)
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
