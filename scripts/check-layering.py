#!/usr/bin/env python3
"""Checks the module layering of docs/architecture.md against the code.

Reads the table between the "layering table" markers of docs/architecture.md. For every
source and header file of each module row, it checks that:
  * every `#include <regolith/X/...>` names the module itself or one its row may depend on;
  * no include matches the row's "must not include" list (third-party or system headers);
  * no include of the form `#include "..."` reaches out of the module's own folder;
  * the stateless modules (STATELESS: topo, "no threads, no syscalls, no global state") hold no
    per-thread or mutable static state: no `thread_local`, no `static std::atomic`/`std::mutex`.
Prints one line per violation (file:line: what, and the rule) and exits 1 if there is any.

    python3 scripts/check-layering.py [repository root]
"""

import pathlib
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')
STATELESS = {"topo"}
STATE = re.compile(r'\bthread_local\b|\bstatic\s+(?:inline\s+)?std::(?:atomic|mutex)\b')
SOURCES = {".cpp", ".hpp", ".h", ".cc", ".inl"}


def cells(line):
    return [c.strip() for c in line.strip().strip("|").split("|")]


def names(cell):
    """Backticked or comma-separated names of a table cell."""
    ticked = re.findall(r"`([^`]+)`", cell)
    if ticked:
        return ticked
    return [n.strip() for n in cell.split(",") if n.strip()]


def read_table(doc):
    text = doc.read_text(encoding="utf-8").splitlines()
    try:
        start = next(i for i, l in enumerate(text) if "layering table" in l and "<!--" in l)
        end = next(i for i, l in enumerate(text) if "end of layering table" in l)
    except StopIteration:
        sys.exit(f"check-layering: {doc}: no layering table markers, expected "
                 "'<!-- layering table ... -->' and '<!-- end of layering table -->'")
    rows = [cells(l) for l in text[start + 1:end] if l.strip().startswith("|")]
    header, rows = rows[0], [r for r in rows[2:]]
    want = ["folder", "may depend on", "must not include"]
    for w in want:
        if w not in header:
            sys.exit(f"check-layering: {doc}: layering table has columns {header}, expected {want}")
    col = {h: i for i, h in enumerate(header)}
    table = {}
    for r in rows:
        folder = names(r[col["folder"]])[0].strip("/")
        table[folder] = {
            "deps": set(names(r[col["may depend on"]])),
            "forbidden": names(r[col["must not include"]]),
        }
    return table


def module_of(folder):
    """The Regolith module name a folder's headers live under (bindings/python: none)."""
    return folder.split("/")[0]


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).parent.parent)
    table = read_table(root / "docs" / "architecture.md")
    modules = {module_of(f) for f in table}
    problems = []
    checked = 0
    for folder, rule in table.items():
        base = root / folder
        if not base.is_dir():
            problems.append(f"{folder}: folder named in docs/architecture.md does not exist")
            continue
        self_name = module_of(folder)
        allowed = rule["deps"] | {self_name}
        unknown = rule["deps"] - modules
        if unknown:
            problems.append(f"docs/architecture.md: {folder} may depend on unknown modules {sorted(unknown)}")
        for path in sorted(base.rglob("*")):
            if path.suffix not in SOURCES or not path.is_file():
                continue
            checked += 1
            rel = path.relative_to(root)
            for n, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
                code = line.split("//")[0]
                if self_name in STATELESS and STATE.search(code):
                    problems.append(f"{rel}:{n}: holds per-thread or static state ({STATE.search(code).group(0)}), "
                                    f"but {folder} has no global state (docs/architecture.md)")
                m = INCLUDE.match(line)
                if not m:
                    continue
                kind, target = m.groups()
                if kind == "<" and target.startswith("regolith/"):
                    mod = target.split("/")[1]
                    if mod not in allowed:
                        problems.append(f"{rel}:{n}: includes <{target}>, but {folder} may depend on "
                                        f"{', '.join(sorted(rule['deps'])) or 'nothing'} only")
                elif kind == '"':
                    resolved = (path.parent / target).resolve()
                    if base.resolve() not in resolved.parents and not (root / "tests").resolve() in resolved.parents:
                        problems.append(f"{rel}:{n}: includes \"{target}\" from outside {folder}/, "
                                        "expected a public header <regolith/...>")
                for bad in rule["forbidden"]:
                    if target == bad or target.startswith(bad):
                        problems.append(f"{rel}:{n}: includes {target}, which {folder} must not include")
    for p in problems:
        print(p)
    if problems:
        print(f"check-layering: {len(problems)} violations of docs/architecture.md in {checked} files")
        return 1
    print(f"check-layering: {checked} files of {len(table)} modules follow docs/architecture.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
