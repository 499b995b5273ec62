"""bench/compare end to end on a tiny map, without OctoMap: every comparison row is printed (both
presets at each thread count and the context + recycle row, and the public path's four rows, for
both maps, two interleaved rounds). Its output lines are checked, never its timings. usage: bench_compare_smoke.py SOURCE_DIR BUILD_DIR"""
import subprocess
import sys

src, build = sys.argv[1], sys.argv[2]
out = subprocess.run([sys.executable, f"{src}/bench/compare", "--build", build, "--dims", "24", "20", "12",
                      "--repeats", "1", "--rounds", "2", "--threads", "1", "2", "--no-fusion"],
                     check=True, capture_output=True, text=True).stdout
rows = [line for line in out.splitlines() if "scipy/occseg =" in line and "] public " not in line]
public = [line for line in out.splitlines() if "] public " in line and "call/stages =" in line]
recycled = [line for line in rows if "threads 2, context + recycle:" in line]
print(out)
if len(rows) != 10 or len(recycled) != 2:
    sys.exit(f"expected 10 comparison rows (2 of them context + recycle), got {len(rows)} ({len(recycled)})")
# The public path: Python one-shot and context, C borrowed and C copy, for each map.
for name in ("python one-shot", "python context + recycle", "C borrowed map + labels view", "C copy in + labels copy out"):
    if sum(f"] public {name}" in line for line in public) != 2:
        sys.exit(f"expected a 'public {name}' row per map in:\n" + "\n".join(public))
