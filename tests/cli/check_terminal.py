"""`occseg` in a terminal session (a pseudo-terminal, as a user's shell gives it): a long job
draws a progress bar on stderr; without a terminal, or with --quiet, there is none; Ctrl-C (the
terminal's interrupt character) and SIGTERM stop the job with exit code 130 / 143 and leave no
output file behind, and the files of an earlier run as they were."""
import glob
import os
import pty
import re
import select
import signal
import subprocess
import sys
import time

occseg, work, data = sys.argv[1], sys.argv[2], sys.argv[3]
BAR = re.compile(r"occseg: [\w .:-]+ \[[#.]{30}\] +\d+%  [\d.]+ s\x1b\[K")


def in_terminal(args, interrupt=None, when="", deadline=300, env=None):
    """Runs occseg with stdin, stdout and stderr on a new pseudo-terminal (its controlling
    terminal). interrupt: None, b"\\x03" (typed Ctrl-C) or a signal number, sent once the progress
    bar shows with `when` in its label. Returns (exit code, everything the terminal received)."""
    pid, fd = pty.fork()
    if pid == 0:
        os.chdir(work)
        os.execve(occseg, [occseg, *args], {**os.environ, **(env or {})})
    seen, sent, end = b"", False, time.time() + deadline
    while time.time() < end:
        ready, _, _ = select.select([fd], [], [], 1.0)
        if not ready:
            continue
        try:
            chunk = os.read(fd, 65536)
        except OSError:  # EIO: the child closed the terminal
            break
        if not chunk:
            break
        seen += chunk
        if interrupt is not None and not sent and any(when in b for b in BAR.findall(seen.decode(errors="replace"))):
            if isinstance(interrupt, bytes):
                os.write(fd, interrupt)
            else:
                os.kill(pid, interrupt)
            sent = True
    else:
        os.kill(pid, signal.SIGKILL)
        raise AssertionError(f"{args}: no end within {deadline} s; got {seen[-500:]!r}")
    _, status = os.waitpid(pid, 0)
    os.close(fd)
    assert interrupt is None or sent, f"{args}: the bar never showed, so nothing was interrupted: {seen!r}"
    return os.waitstatus_to_exitcode(status), seen.decode(errors="replace")


# A long job (over a second: the bar shows after 0.5 s): the cone scene in a 320 x 320 x 256
# map, segmented on one thread; reading, segmenting and writing take 0.2, 0.3 and 0.6 s.
r = subprocess.run([occseg, "simulate", "--scene", "cone", "--dims", "320", "320", "256", "--out", "sim"], cwd=work,
                   capture_output=True, text=True)
assert r.returncode == 0, r.stderr
job = ["segment", "sim/map.npy", "--voxel-size", "0.04", "--threads", "1"]

code, text = in_terminal(job + ["--out", "seg"])
assert code == 0, (code, text)
bars = BAR.findall(text)
assert bars and any("segmenting: " in b or "writing " in b for b in bars), text
assert "\r" in text and "written: seg/labels.nrrd" in text, text
assert sorted(os.listdir(os.path.join(work, "seg"))) == ["labels.nrrd", "scene.png", "segmentation.png", "segments.json"]
# Reading and writing report their progress too (issue 27: the bar stayed at 0 % through both):
# each phase redraws at every whole percent, so the bar shows how far each got before the next
# (the bar from the start, OCCSEG_PROGRESS_DELAY=0, so that the reading shows at all).
code, text = in_terminal(job + ["--out", "seg_progress"], env={"OCCSEG_PROGRESS_DELAY": "0"})
assert code == 0, (code, text)
def percents(label):
    return [int(m) for m in re.findall(re.escape("occseg: " + label) + r" \[[#.]+\] +(\d+)%", text)]
assert percents("reading map.npy") and max(percents("reading map.npy")) == 100, text
# labels.nrrd is the first of four files (scene.png the last): the bar goes from 0 to a quarter while it is written.
assert percents("writing labels.nrrd") and max(percents("writing labels.nrrd")) >= 20, text

# No terminal (pipes), or --quiet: no bar, nothing on stderr.
r = subprocess.run([occseg, *job, "--out", "seg_pipe"], cwd=work, capture_output=True, text=True)
assert r.returncode == 0 and r.stderr == "" and "\r" not in r.stdout, r.stderr
code, text = in_terminal(job + ["--out", "seg_quiet", "--quiet"])
assert code == 0 and text == "", (code, text)

# Ctrl-C typed in the terminal during the segmentation: it stops at the next stage (or, should
# the segmentation be over by then, after the file being written): exit 130, one message, no
# output left. The bar shows from the start (OCCSEG_PROGRESS_DELAY=0): the whole segmentation
# now takes less than the default 0.5 s delay.
now = {"OCCSEG_PROGRESS_DELAY": "0"}
code, text = in_terminal(job + ["--out", "seg_int"], interrupt=b"\x03", when="segmenting: ", env=now)
assert code == 130, (code, text)
assert "occseg: interrupted: stopped; no output file was changed" in text, text
assert not os.path.exists(os.path.join(work, "seg_int")), os.listdir(os.path.join(work, "seg_int"))

# The same into an existing directory: it stays, and so does what was in it before.
os.makedirs(os.path.join(work, "keep"))
with open(os.path.join(work, "keep", "notes.txt"), "w") as f:
    f.write("mine\n")
code, text = in_terminal(job + ["--out", "keep"], interrupt=b"\x03", when="segmenting: ", env=now)
assert code == 130 and os.listdir(os.path.join(work, "keep")) == ["notes.txt"], (code, os.listdir(os.path.join(work, "keep")))

# Ctrl-C during a re-run into the folder of the first run, while the new files are being
# written (labels.npy is complete then): the first run's files stay exactly as they were. Should
# the signal come only once every file is in place, the run ends normally with the whole new set.
def files_of(d):
    p = os.path.join(work, d)
    return {f: open(os.path.join(p, f), "rb").read() for f in sorted(os.listdir(p))}


first = files_of("seg")
rerun = job + ["--preset", "paper"]
code, text = in_terminal(rerun + ["--out", "seg"], interrupt=b"\x03", when="writing labels.nrrd", env=now)
if code == 130:
    assert files_of("seg") == first, f"the first run's files changed: {sorted(files_of('seg'))}"
else:
    assert code == 0, (code, text)
    r = subprocess.run([occseg, *rerun, "--out", "seg_paper"], cwd=work, capture_output=True, text=True)
    assert r.returncode == 0 and files_of("seg") == files_of("seg_paper"), r.stderr
assert not glob.glob(os.path.join(work, "seg", "*.tmp-*"))

# Fusing a point cloud reports through ScanOptions::progress: with the bar shown from the start
# (OCCSEG_PROGRESS_DELAY=0), "fusing scans" appears after the first 65536 of its 254456 rays, and
# Ctrl-C then stops the job.
cloud = ["segment", os.path.join(data, "office1.pcd"), "--voxel-size", "0.02", "--threads", "1"]
code, text = in_terminal(cloud + ["--out", "cloud_int"], interrupt=b"\x03", when="fusing scans",
                         env={"OCCSEG_PROGRESS_DELAY": "0"})
assert code == 130 and not os.path.exists(os.path.join(work, "cloud_int")), (code, text)
assert re.search(r"occseg: fusing scans \[#*\.*\] +\d+%", text), text

# The demo, stopped by SIGTERM while it simulates or segments: exit 143, no occseg-out.
code, text = in_terminal(["demo", "--threads", "1"], interrupt=signal.SIGTERM)
assert code == 143 and "occseg: terminated" in text, (code, text)
assert not os.path.exists(os.path.join(work, "occseg-out"))
assert not glob.glob(os.path.join(work, "**", "*.tmp-*"), recursive=True)
print("cli terminal: all checks passed")
