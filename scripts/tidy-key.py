#!/usr/bin/env python3
"""Prints the clang-tidy cache key of one source file, or writes a PCH-free compile database.

    tidy-key.py strip-pch <build>/compile_commands.json <out folder>
        Writes <out folder>/compile_commands.json without CMake's precompiled-header
        arguments (GCC's .gch files are not clang's; the sources include what they use).
    tidy-key.py key <compile_commands.json> <source> <repository root> <extra>
        Prints a SHA-256 over everything clang-tidy's findings for <source> depend on: the
        clang-tidy version, every .clang-tidy of the repository, <extra> (extra arguments),
        the source's path relative to the root, and its preprocessed text with comments
        (NOLINT) and without line markers, as the compiler of its build command produces it.
        scripts/run-clang-tidy.sh skips a file whose key a clean run has recorded.
"""

import hashlib
import json
import pathlib
import shlex
import subprocess
import sys


def args_of(entry):
    return entry["arguments"] if "arguments" in entry else shlex.split(entry["command"])


def without_pch(args):
    out, skip = [], False
    for i, a in enumerate(args):
        if skip:
            skip = False
            continue
        if a == "-include" and i + 1 < len(args) and "cmake_pch" in args[i + 1]:
            skip = True
            continue
        if a.startswith("-include") and "cmake_pch" in a:
            continue
        if a == "-Winvalid-pch":
            continue
        out.append(a)
    return out


def strip_pch(db_path, out_dir):
    db = json.loads(pathlib.Path(db_path).read_text())
    for e in db:
        e["arguments"] = without_pch(args_of(e))
        e.pop("command", None)
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "compile_commands.json").write_text(json.dumps(db))


def preprocess_args(args):
    out, skip = [], False
    for a in args:
        if skip:
            skip = False
            continue
        if a in ("-o", "-MT", "-MF", "-MQ"):
            skip = True
            continue
        if a in ("-c", "-MD", "-MMD"):
            continue
        out.append(a)
    return out + ["-E", "-P", "-C", "-o", "-"]


def key(db_path, source, root, extra):
    root = pathlib.Path(root).resolve()
    source = pathlib.Path(source).resolve()
    db = json.loads(pathlib.Path(db_path).read_text())
    entry = next(e for e in db if pathlib.Path(e["directory"], e["file"]).resolve() == source)
    h = hashlib.sha256()
    version = subprocess.run(["clang-tidy", "--version"], capture_output=True, text=True).stdout
    h.update(version.encode())
    for cfg in sorted(root.rglob(".clang-tidy")):
        if "build" in cfg.relative_to(root).parts[0]:
            continue
        h.update(str(cfg.relative_to(root)).encode())
        h.update(cfg.read_bytes())
    h.update(extra.encode())
    h.update(str(source.relative_to(root)).encode())
    pre = subprocess.run(preprocess_args(without_pch(args_of(entry))), cwd=entry["directory"],
                         capture_output=True)
    if pre.returncode != 0:
        return None
    # __FILE__ expands to absolute paths: the same checkout in another folder has the same key.
    h.update(pre.stdout.replace(str(root).encode(), b"<root>"))
    return h.hexdigest()


def main():
    if sys.argv[1] == "strip-pch":
        strip_pch(sys.argv[2], sys.argv[3])
        return 0
    k = key(sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5] if len(sys.argv) > 5 else "")
    if k is None:
        return 1
    print(k)
    return 0


if __name__ == "__main__":
    sys.exit(main())
