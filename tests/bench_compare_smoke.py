"""bench/compare end to end on a tiny map, without OctoMap: every comparison row is printed (both
presets at each thread count and the context + recycle row, for both maps, two interleaved
rounds). Its output lines are checked, never its timings. usage: bench_compare_smoke.py SOURCE_DIR BUILD_DIR"""
import subprocess
import sys

src, build = sys.argv[1], sys.argv[2]
out = subprocess.run([sys.executable, f"{src}/bench/compare", "--build", build, "--dims", "24", "20", "12",
                      "--repeats", "1", "--rounds", "2", "--threads", "1", "2", "--no-fusion"],
                     check=True, capture_output=True, text=True).stdout
rows = [line for line in out.splitlines() if "scipy/occseg =" in line]
recycled = [line for line in rows if "threads 2, context + recycle:" in line]
print(out)
if len(rows) != 10 or len(recycled) != 2:
    sys.exit(f"expected 10 comparison rows (2 of them context + recycle), got {len(rows)} ({len(recycled)})")
