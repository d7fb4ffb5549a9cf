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
    tidy-key.py deps-keys <build>/compile_commands.json <repository root> <extra> <build>
        Prints "<source>\t<key>" for every source of the database whose object the build
        folder's ninja has valid dependencies for: a SHA-256 over the clang-tidy version,
        every .clang-tidy, <extra>, the source's path relative to the root, its compile
        arguments, and the path and contents of every file the compiler read for it (the
        source, every header, system headers too: `ninja -t deps`; for an object compiled
        with a precompiled header, the header's own). The same inputs as the key above,
        read from disk instead of preprocessed: all keys of a build in a few seconds, where
        preprocessing each file took CI about 3 minutes on 2 cores. A source without valid
        dependencies gets no line (the caller falls back to the key above).
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


def common_inputs(h, root, extra, version):
    """Hashes what every key shares: the clang-tidy version, every .clang-tidy of the
    repository (build folders left out) and the extra arguments."""
    h.update(version.encode())
    for cfg in sorted(root.rglob(".clang-tidy")):
        if "build" in cfg.relative_to(root).parts[0]:
            continue
        h.update(str(cfg.relative_to(root)).encode())
        h.update(cfg.read_bytes())
    h.update(extra.encode())


def key(db_path, source, root, extra):
    root = pathlib.Path(root).resolve()
    source = pathlib.Path(source).resolve()
    db = json.loads(pathlib.Path(db_path).read_text())
    entry = next(e for e in db if pathlib.Path(e["directory"], e["file"]).resolve() == source)
    h = hashlib.sha256()
    version = subprocess.run(["clang-tidy", "--version"], capture_output=True, text=True).stdout
    common_inputs(h, root, extra, version)
    h.update(str(source.relative_to(root)).encode())
    pre = subprocess.run(preprocess_args(without_pch(args_of(entry))), cwd=entry["directory"],
                         capture_output=True)
    if pre.returncode != 0:
        return None
    # __FILE__ expands to absolute paths: the same checkout in another folder has the same key.
    h.update(pre.stdout.replace(str(root).encode(), b"<root>"))
    return h.hexdigest()


def ninja_deps(build_dir):
    """{object path relative to the build folder: [file paths]} of the objects whose
    dependencies ninja holds as valid."""
    out = subprocess.run(["ninja", "-C", str(build_dir), "-t", "deps"], capture_output=True,
                         text=True, check=True).stdout
    deps, current = {}, None
    for line in out.splitlines():
        if not line.strip():
            current = None
        elif not line.startswith(" "):
            target, _, status = line.partition(": #deps")
            current = [] if status.rstrip().endswith("(VALID)") else None
            if current is not None:
                deps[target] = current
        elif current is not None:
            current.append(line.strip())
    return deps


def deps_keys(db_path, root, extra, build_dir):
    root = pathlib.Path(root).resolve()
    build_dir = pathlib.Path(build_dir).resolve()
    db = json.loads(pathlib.Path(db_path).read_text())
    version = subprocess.run(["clang-tidy", "--version"], capture_output=True, text=True).stdout
    base = hashlib.sha256(b"tidy-key deps 1\n")
    common_inputs(base, root, extra, version)
    deps = ninja_deps(build_dir)
    digests = {}

    def digest(path):
        if path not in digests:
            try:
                digests[path] = hashlib.sha256(pathlib.Path(path).read_bytes()).hexdigest()
            except OSError:
                digests[path] = None
        return digests[path]

    def normalised(path):
        return path.replace(str(root), "<root>")

    for entry in db:
        original = args_of(entry)
        args = without_pch(original)
        source = pathlib.Path(entry["directory"], entry["file"]).resolve()
        obj = args[args.index("-o") + 1] if "-o" in args else None
        files = deps.get(obj) if obj else None
        if not files:
            continue
        files = list(files)
        # The command's precompiled header: the files it read are the object's too.
        for i, a in enumerate(original):
            if a == "-include" and i + 1 < len(original) and "cmake_pch" in original[i + 1]:
                pch = pathlib.Path(original[i + 1] + ".gch")
                pch_deps = deps.get(str(pch.relative_to(build_dir)) if pch.is_absolute() else str(pch))
                if not pch_deps:
                    files = None
                    break
                files += pch_deps
        if files is None:
            continue
        h = base.copy()
        h.update(str(source.relative_to(root)).encode())
        h.update("\0".join(normalised(a) for a in preprocess_args(args)).encode())
        # In the order of their paths as the key writes them: ninja holds a path as the
        # compiler wrote it, relative to the build folder or absolute (a ccache hit's).
        paths = {normalised(str((build_dir / f).resolve())): str((build_dir / f).resolve())
                 for f in files}
        ok = True
        for written in sorted(paths):
            d = digest(paths[written])
            if d is None:
                ok = False
                break
            h.update(written.encode())
            h.update(d.encode())
        if ok:
            print(f"{source}\t{h.hexdigest()}")


def main():
    if sys.argv[1] == "deps-keys":
        deps_keys(sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5])
        return 0
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
