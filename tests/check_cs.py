#!/usr/bin/env python3
"""No imaginary part is dropped silently in the complex-step builds (lib/linalg/scalar.h).

A value of type ap_sc that reaches a double (an assignment, an argument, fabs, sqrt) loses its
imaginary part, which is exactly the derivative. The compiler says so under -Wconversion
("conversion from 'complex double' to 'double' discards imaginary component"); the build
itself does not use -Wconversion (it would flag every int narrowing), so this check compiles
every *_cs.c translation unit of compile_commands.json again, syntax only, with it, and fails
on any such warning (and on -Wabsolute-value: fabs of a complex value). Decisions take real
parts on purpose, through SC_RE / SC_MAG, which are explicit and do not warn.

Usage: check_cs.py BUILD_DIR. Exit 0 when clean, 1 otherwise (the warnings are printed).
"""
import json
import os
import shlex
import subprocess
import sys

PHRASES = ("discards imaginary component", "-Wabsolute-value")


def main():
    build = sys.argv[1] if len(sys.argv) > 1 else "build"
    with open(os.path.join(build, "compile_commands.json")) as f:
        entries = [e for e in json.load(f) if e["file"].endswith("_cs.c")]
    if not entries:
        print("check_cs: no *_cs.c translation unit in compile_commands.json")
        return 1
    bad = 0
    for e in entries:
        cmd = shlex.split(e["command"]) if "command" in e else list(e["arguments"])
        out = []
        skip = False
        for c in cmd:   # drop -o FILE, -MD/-MQ/-MF dependency outputs and -Werror
            if skip:
                skip = False
                continue
            if c in ("-o", "-MQ", "-MF"):
                skip = True
                continue
            if c in ("-MD", "-Werror"):
                continue
            out.append(c)
        out += ["-fsyntax-only", "-fdiagnostics-color=never", "-Wconversion",
                "-Wno-sign-conversion", "-Wabsolute-value"]
        r = subprocess.run(out, cwd=e["directory"], capture_output=True, text=True)
        lines = [l for l in r.stderr.splitlines() if any(p in l for p in PHRASES)]
        if r.returncode != 0:
            print(r.stderr)
            bad += 1
        for l in lines:
            print(l)
        bad += len(lines)
        print("check_cs: %-40s %d" % (os.path.relpath(e["file"], e["directory"]), len(lines)))
    print("check_cs: %d translation units, %d problems" % (len(entries), bad))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
