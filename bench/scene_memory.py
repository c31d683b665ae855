#!/usr/bin/python3
"""Peak memory and result of `appell check` on hostile scenes (docs/scenes.md "Limits").

    bench/scene_memory.py [APPELL] [--limit-gb G] [--keys N]

Writes into a temporary directory:
  bomb20k.yaml   a 20 000-character explicit key whose value is a tree of aliases (10^5 nodes)
  bomb2m.yaml    the same with a 2 000 000-character key
  flow16m.yaml   one flow sequence of 8 million numbers (16 MiB)
  keysN.yaml     a mapping of N (default 100 000) keys under bodies:
and runs `APPELL check` on each under an address-space limit of G GiB (default 8, so that a
loader without limits fails instead of taking the machine), printing the exit code, the peak
resident memory of the child (wait4's rusage, MB), the first 100 characters of the message and the
CPU time. APPELL defaults to build/tools/appell.
"""
import os
import resource
import subprocess
import sys
import tempfile


def alias_tree(key):
    v = "[&a [x, x, x, x, x, x, x, x, x, x]"
    prev = "a"
    for name in "bcde":
        v += f", &{name} [" + ", ".join([f"*{prev}"] * 10) + "]"
        prev = name
    v += ", " + ", ".join(["*d"] * 7) + "]"
    return "? " + key + "\n: " + v + "\n"


def write(d, nkeys):
    files = {
        "bomb20k.yaml": alias_tree("k" * 20000),
        "bomb2m.yaml": alias_tree("k" * 2000000),
        "flow16m.yaml": "a: [" + "1," * ((16 << 20) // 2 - 11) + "1]\n",
        f"keys{nkeys}.yaml": "bodies:\n" + "".join(f"  b{i}: 1\n" for i in range(nkeys)),
    }
    for name, text in files.items():
        with open(os.path.join(d, name), "w") as f:
            f.write(text)
    return list(files)


def run(appell, path, limit):
    def setup():
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    with tempfile.TemporaryFile() as err:
        p = subprocess.Popen([appell, "check", path], stdout=subprocess.DEVNULL, stderr=err,
                             preexec_fn=setup)
        _, status, use = os.wait4(p.pid, 0)   # this child's own peak, not all children's
        p.returncode = os.waitstatus_to_exitcode(status)
        err.seek(0)
        msg = err.read().decode(errors="replace").strip()
    msg = msg.replace(path, os.path.basename(path))
    return p.returncode, use.ru_maxrss / 1024.0, msg[:100], use.ru_utime + use.ru_stime


def main():
    args = sys.argv[1:]
    limit_gb, nkeys = 8.0, 100000
    for opt in ("--limit-gb", "--keys"):
        if opt in args:
            i = args.index(opt)
            if opt == "--limit-gb":
                limit_gb = float(args[i + 1])
            else:
                nkeys = int(args[i + 1])
            del args[i:i + 2]
    appell = args[0] if args else "build/tools/appell"
    with tempfile.TemporaryDirectory() as d:
        for name in write(d, nkeys):
            code, rss, msg, cpu = run(appell, os.path.join(d, name), int(limit_gb * (1 << 30)))
            print(f"{name:16} exit {code}  peak {rss:9.1f} MB  cpu {cpu:7.2f} s  {msg}")
            sys.stdout.flush()


if __name__ == "__main__":
    main()
