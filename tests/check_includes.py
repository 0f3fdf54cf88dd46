#!/usr/bin/env python3
"""check_includes.py — the include rule of the style guide: arrows run server -> proto -> core,
and no cycles, neither among the files of one folder nor among folders.

The graph is of files. A file including a header depends on it; a header depends on the .c
files defining the functions it declares (calling them is using that code), except that a .c
file including the header it implements does not thereby depend on it. So a cycle is a real
mutual use: a.c calls b.c, which calls a.c (through their headers), or a header whose
implementation includes it back through another header. Types-only headers (x_types.h) have
no implementation and end the chain. Prints each cycle; exit status 1 when there is any.

    python3 tests/check_includes.py [ROOT]
"""
import collections
import os
import re
import sys

LAYERS = ["core", "proto", "server"]  # each may include only its own and the earlier ones
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
COMMENT = re.compile(r"/\*.*?\*/|//[^\n]*", re.S)
# A function definition at file scope: a line starting in column 0 with a return type, then
# name(parameters) and the body's brace (possibly after the parameters' continuation lines).
DEFINITION = re.compile(r"^(?!static\b)(?!typedef\b)[A-Za-z_][\w \t\*]*?\b([A-Za-z_]\w*)\s*\([^;{}]*\)\s*\{",
                        re.M)
NAME_CALL = re.compile(r"\b([A-Za-z_]\w*)\s*\(")


def sources(root):
    out = {}
    for top in LAYERS:
        for d, _, fs in os.walk(os.path.join(root, top)):
            for f in fs:
                if f.endswith((".c", ".h", ".cc")):
                    p = os.path.relpath(os.path.join(d, f), root)
                    with open(os.path.join(root, p), errors="replace") as fh:
                        out[p] = fh.read()
    return out


def graph(root):
    text = sources(root)
    code = {p: COMMENT.sub(" ", t) for p, t in text.items()}
    defined = collections.defaultdict(set)  # function name -> .c files defining it
    for p, c in code.items():
        if not p.endswith(".h"):
            for name in DEFINITION.findall(c):
                defined[name].add(p)
    implements = collections.defaultdict(set)  # header -> .c files defining what it declares
    for p, c in code.items():
        if p.endswith(".h"):
            for name in set(NAME_CALL.findall(c)):
                implements[p] |= defined.get(name, set())
            implements[p].discard(p)
    declares = {p for p in code if p.endswith(".h") and implements[p]}
    edges = collections.defaultdict(set)
    for p, t in text.items():
        for inc in INCLUDE.findall(t):
            h = inc if inc in text else os.path.normpath(os.path.join(os.path.dirname(p), inc))
            if h in text and p not in implements[h]:
                a, b = node(p, declares), node(h, declares)
                if a != b:
                    edges[a].add(b)
    return edges


def node(path, declares):
    """A file's module: x.c and x.h are one (x.h declares what x.c defines), except that a
    header declaring no function (types only) is a module of its own."""
    stem, ext = os.path.splitext(path)
    return path if ext == ".h" and path not in declares else stem


def cycles(edges):
    """Strongly connected components with more than one file (Tarjan, iterative)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]
    for start in sorted(edges):
        if start in index:
            continue
        work = [(start, iter(sorted(edges.get(start, ()))))]
        index[start] = low[start] = counter[0]
        counter[0] += 1
        stack.append(start)
        on.add(start)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(edges.get(w, ())))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return out


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    edges = graph(root)
    problems = []
    for a, bs in sorted(edges.items()):
        for b in sorted(bs):
            la, lb = LAYERS.index(a.split(os.sep)[0]), LAYERS.index(b.split(os.sep)[0])
            if lb > la:
                problems.append(f"layer: {a} uses {b} ({LAYERS[lb]} is above {LAYERS[la]})")
    inside = {a: {b for b in bs if os.path.dirname(b) == os.path.dirname(a)} for a, bs in edges.items()}
    for c in cycles(inside):
        problems.append("cycle in " + os.path.dirname(c[0]) + ": " + " ".join(os.path.basename(x) for x in c))
    folders = collections.defaultdict(set)
    for a, bs in edges.items():
        for b in bs:
            if os.path.dirname(a) != os.path.dirname(b):
                folders[os.path.dirname(a)].add(os.path.dirname(b))
    for c in cycles(folders):
        problems.append("cycle between folders: " + " ".join(c))
    for p in problems:
        print(p)
    print(f"check_includes: {sum(len(b) for b in edges.values())} dependencies, {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
