#!/usr/bin/env python3
"""A mutation fuzzer of appell.loads (the Python package's scene loader; not part of CI).

Seeds: the scenes of examples/scenes and tests/scenes. Each input is a seed mutated by a few
random edits (byte flips, deletions, insertions of YAML punctuation or of a slice of another
seed, duplications of a slice), as str or bytes, with a random override now and then; appell.loads
must return a Model or raise appell.Error / ValueError / TypeError / UnicodeError, nothing
else, and must not crash the interpreter. The inputs run in a child interpreter that writes each
one to a file before loading it: when the child dies (a signal, a sanitizer), the parent saves
that input to tests/fuzz/crashes/loads-* and stops with a non-zero status.

Usage: PYTHONPATH=build/python tests/fuzz/fuzz_loads.py [SECONDS] [SEED]   (scripts/fuzz loads)
Prints the number of executed inputs and how they ended."""

import os
import random
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PUNCT = [b":", b"- ", b"{", b"}", b"[", b"]", b",", b"&a ", b"*a", b"<<: ", b"\n  ", b"'", b'"',
         b"!!", b"1e308", b"-0", b"nan", b".inf", b"1/0", b"x^0.5", b"\t", b"\x00", b"\xff",
         b"#", b"---\n", b"...\n", b"?", b"|", b">"]
SETS = ["bodies.disk.mass=-1", "simulation.t_end=1e300", "initial.x.y=1", "a=b=c", "=",
        "simulation.method=bdf", "output.interval=1e-300", "bodies=1"]


def seeds():
    out = []
    for d in ("examples/scenes", "tests/scenes"):
        out += [p.read_bytes() for p in sorted((ROOT / d).glob("*.yaml"))]
    return out


def mutate(rng, corpus):
    b = bytearray(rng.choice(corpus))
    for _ in range(rng.randint(1, 8)):
        i = rng.randrange(len(b) + 1)
        k = rng.random()
        if k < 0.25 and b:
            b[min(i, len(b) - 1)] ^= 1 << rng.randrange(8)
        elif k < 0.45:
            del b[i:i + rng.randint(1, 16)]
        elif k < 0.75:
            b[i:i] = rng.choice(PUNCT)
        elif k < 0.9:
            o = rng.choice(corpus)
            j = rng.randrange(len(o) + 1)
            b[i:i] = o[j:j + rng.randint(1, 200)]
        else:
            j = rng.randrange(len(b) + 1)
            b[i:i] = b[j:j + rng.randint(1, 400)] * rng.randint(1, 8)
    return bytes(b)


def child(seconds, seed, last):
    import appell
    rng = random.Random(seed)
    corpus = seeds()
    counts = {}
    end = time.monotonic() + seconds
    n = 0
    while time.monotonic() < end:
        data = mutate(rng, corpus)
        text = data if rng.random() < 0.5 else data.decode("utf-8", "replace")
        sets = [rng.choice(SETS)] if rng.random() < 0.1 else None
        with open(last, "wb") as f:
            f.write(data)
        try:
            appell.loads(text, name="fuzz.yaml", set=sets)
            what = "loaded"
        except (appell.Error, ValueError, TypeError, UnicodeError) as e:
            what = type(e).__name__
        counts[what] = counts.get(what, 0) + 1
        n += 1
    print(n, " ".join(f"{k}={v}" for k, v in sorted(counts.items())), flush=True)


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        child(float(sys.argv[2]), int(sys.argv[3]), sys.argv[4])
        return 0
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 600
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else int(time.time())
    last = f"/tmp/appell-fuzz-loads-{os.getpid()}.yaml"
    r = subprocess.run([sys.executable, __file__, "--child", str(seconds), str(seed), last],
                       capture_output=True, text=True)
    if r.returncode != 0:
        crashes = ROOT / "tests/fuzz/crashes"
        crashes.mkdir(exist_ok=True)
        dest = crashes / f"loads-{seed}"
        dest.write_bytes(Path(last).read_bytes())
        print(f"fuzz_loads: the child ended with {r.returncode}; input saved to {dest}\n"
              f"{r.stderr[-2000:]}", file=sys.stderr)
        return 1
    os.unlink(last)
    execs, *how = r.stdout.split()
    print(f"fuzz_loads: {execs} inputs in {seconds:g} s (seed {seed}): {' '.join(how)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
