"""`occseg` conventions as a user meets them: --version, --help for the tool and every
subcommand, usage errors (exit 1) and bad input (exit 2) as one line on stderr, nothing on stdout."""
import os
import re
import subprocess
import sys

occseg, work = sys.argv[1], sys.argv[2]
SUBCOMMANDS = ["demo", "segment", "info", "simulate", "evaluate", "figures", "plugins"]


def run(*args, cwd=work):
    return subprocess.run([occseg, *args], capture_output=True, text=True, cwd=cwd, timeout=120)


def one_line_error(r, code, *words):
    assert r.returncode == code, (r.args, r.returncode, r.stderr)
    assert r.stdout == "", (r.args, r.stdout)
    assert r.stderr.count("\n") == 1 and r.stderr.endswith("\n"), (r.args, r.stderr)
    assert r.stderr.startswith("occseg: "), r.stderr
    for w in words:
        assert w in r.stderr, (r.args, w, r.stderr)


r = run("--version")
assert r.returncode == 0 and re.fullmatch(r"occseg \d+\.\d+\.\d+\n", r.stdout), (r.returncode, r.stdout)

r = run("--help")
assert r.returncode == 0 and r.stderr == "", r.stderr
for sub in SUBCOMMANDS:
    assert re.search(rf"^\s+{sub}\s", r.stdout, re.M), (sub, r.stdout)
for text in ("Exit codes", "130", "Without a subcommand, runs `occseg demo`"):
    assert text in r.stdout, (text, r.stdout)

for sub in SUBCOMMANDS:
    r = run(sub, "--help")
    assert r.returncode == 0, (sub, r.returncode, r.stderr)
    assert r.stdout.splitlines()[1].startswith(f"Usage: occseg {sub} "), (sub, r.stdout[:200])
# The pipeline commands list every parameter --param takes, with its default.
for sub in ("segment", "demo", "info"):
    r = run(sub, "--help")
    for text in ("--preset", "--param", "--threads", "--json", "--quiet", "smax (int, default 64",
                 "free_below (double, default 0.498", "texture (string, default auto)"):
        assert text in r.stdout, (sub, text)

# Usage errors: exit 1, one line naming the problem.
one_line_error(run("bogus"), 1, "bogus")
one_line_error(run("segment"), 1, "input")
one_line_error(run("segment", "map.npy"), 1, "--out")
one_line_error(run("segment", "map.npy", "--out", "o", "--frobnicate"), 1, "--frobnicate")
one_line_error(run("segment", "map.npy", "--out", "o", "--threads", "-1"), 1, "--threads")
one_line_error(run("segment", "map.npy", "--out", "o", "--preset", "fast"), 1, "--preset")
one_line_error(run("info"), 1, "input")
one_line_error(run("demo", "--scene", "moon"), 1, "--scene")
one_line_error(run("--threads", "2"), 1, "--threads")
# A usage error in the pipeline parameters is found before anything is read or created.
one_line_error(run("segment", "missing.npy", "--out", "o1", "--param", "smax=48"), 1, "smax")
one_line_error(run("segment", "missing.npy", "--out", "o1", "--param", "nosuch=1"), 1, "nosuch")
one_line_error(run("segment", "missing.npy", "--out", "o1", "--param", "smax"), 1, "NAME=VALUE")
one_line_error(run("info", "missing.npy", "--param", "free_below=2"), 1, "free_below")
one_line_error(run("segment", "map.xyz", "--out", "o1"), 1, "map.xyz", ".xyz")
# Bad input: exit 2, one line naming the file; nothing created.
one_line_error(run("segment", "missing.npy", "--out", "o2"), 2, "missing.npy")
one_line_error(run("info", "missing.pcd"), 2, "missing.pcd")
with open(os.path.join(work, "empty.npy"), "wb"):
    pass
one_line_error(run("segment", "empty.npy", "--out", "o3"), 2, "empty.npy")
one_line_error(run("info", "empty.npy"), 2, "empty.npy")
with open(os.path.join(work, "file"), "w") as f:
    f.write("not a directory\n")
one_line_error(run("demo", "--dims", "16", "16", "8", "--out", "file/sub"), 2, "file/sub")
for d in ("o", "o1", "o2", "o3"):
    assert not os.path.exists(os.path.join(work, d)), d
print("cli usage: all checks passed")
