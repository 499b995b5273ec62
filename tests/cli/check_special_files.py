"""Inputs that are not regular files: a FIFO named map.npy made `occseg segment` wait for a writer
forever (and, with its signal handlers restarting the read, ignore Ctrl-C and SIGTERM); a link
to /dev/zero named .npy was read until memory ran out; a FIFO named *.so on OCCSEG_PLUGIN_PATH
hung every command, --version included. Now each is refused at once with exit 2 and a message
naming the file and what it is (a warning for the plugin path, whose other commands go on).
A regression would hang: every run has a time limit, as a guard (a hang fails the check), and
the /dev/zero runs an address-space limit outside sanitizer builds."""
import os
import resource
import subprocess
import sys

import numpy as np

occseg, work, data = sys.argv[1], sys.argv[2], sys.argv[3]
sanitized = bool(os.environ.get("OCCSEG_TEST_NO_OOM"))  # set by CMake in every sanitizer build


def limit_memory():
    if not sanitized:  # sanitizers reserve terabytes of shadow address space
        resource.setrlimit(resource.RLIMIT_AS, (1 << 31, 1 << 31))


def run(*args, env=None):
    return subprocess.run([occseg, *args], capture_output=True, text=True, cwd=work, timeout=60,
                          env={**os.environ, **(env or {})}, preexec_fn=limit_memory)


def one_line_error(r, code, *words):
    assert r.returncode == code, (r.args, r.returncode, r.stderr)
    assert r.stdout == "", (r.args, r.stdout)
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("occseg: error: "), (r.args, r.stderr)
    for w in words:
        assert w in r.stderr, (r.args, w, r.stderr)


for ext in ("npy", "nrrd", "pcd", "graph", "bt", "ot"):
    fifo, zero, null = (os.path.join(work, f"{n}.{ext}") for n in ("fifo", "zero", "null"))
    os.mkfifo(fifo)
    os.symlink("/dev/zero", zero)
    os.symlink("/dev/null", null)
    for path, kind in ((fifo, "FIFO"), (zero, "character device"), (null, "character device")):
        name = os.path.basename(path)
        one_line_error(run("segment", name, "--out", "out"), 2, name, "not a regular file but a " + kind)
        one_line_error(run("info", name), 2, name, kind)
        assert not os.path.exists(os.path.join(work, "out")), path

# evaluate's inputs (segments.json, a simulated scene's scene.json) likewise.
r = run("simulate", "--scene", "cube", "--dims", "32", "32", "16", "--out", "truth")
assert r.returncode == 0, r.stderr
r = run("segment", "truth/map.npy", "--out", "seg", "--quiet", "--outputs", "all")
assert r.returncode == 0, r.stderr
os.mkfifo(os.path.join(work, "fifo.json"))
one_line_error(run("evaluate", "--truth", "truth", "--labels", "seg/labels.npy", "--segments", "fifo.json"), 2,
               "fifo.json", "FIFO")
os.replace(os.path.join(work, "truth", "scene.json"), os.path.join(work, "scene.json.saved"))
os.mkfifo(os.path.join(work, "truth", "scene.json"))
one_line_error(run("evaluate", "--truth", "truth", "--labels", "seg/labels.npy", "--segments", "seg/segments.json"),
               2, "scene.json", "FIFO")

# A FIFO among the plugins: a warning naming it, and the command goes on.
plugins = os.path.join(work, "plugins")
os.mkdir(plugins)
os.mkfifo(os.path.join(plugins, "stuck.so"))
env = {"OCCSEG_PLUGIN_PATH": plugins}
r = run("--version", env=env)
assert r.returncode == 0 and r.stdout.startswith("occseg "), (r.returncode, r.stdout, r.stderr)
assert "warning" in r.stderr and "stuck.so" in r.stderr and "FIFO" in r.stderr, r.stderr
np.save(os.path.join(work, "m.npy"), np.full((8, 8, 8), 0.2, np.float32))
r = run("segment", "m.npy", "--out", "o", "--quiet", env=env)
assert r.returncode == 0 and os.path.exists(os.path.join(work, "o", "labels.nrrd")), (r.returncode, r.stderr)
one_line_error(run("plugins", "--load", os.path.join(plugins, "stuck.so")), 2, "stuck.so", "FIFO")
print("cli special files: all checks passed")
