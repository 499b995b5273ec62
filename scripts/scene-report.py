#!/usr/bin/python3
"""The scene table before and after the object rules (issue 23), on the real files and the
simulated scenes: the columns of docs/experiments.md, "Objects, speckles, pockets".

usage: scripts/scene-report.py [--build build] [--work DIR] [--real-only | --sim-only] [--sim-dims NX NY NZ]
                               [--before NAME=VALUE,...] [--scenes NAME,...] [--reuse]

"before" is the default preset with the rules off (object_gap=0, min_object_voxels=0,
min_pocket_voxels=0, surface_band=0, structure_planes=0, plane_holes=0: the labels of the default preset before the
rules); "after"
is the default preset as it is. `--before surface_band=0` compares with the default preset
without the surface band (rule 10), `--before structure_planes=0` without rule 11,
`--before plane_holes=0` without rule 12 (docs/experiments.md, "The surface band", "Structure and
objects", "Holes in a plane seen edge-on"). Real files are read from ../shared/data/ (relative to
the repository root). `--scenes building` reports the simulated building (its own dims, 5 cm voxels
and rings scans unless --sim-dims is given; docs/experiments.md, "A simulated building"); `--reuse`
keeps simulations already in --work (WORK/sim-SCENE) instead of simulating again."""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.path.join(os.path.dirname(ROOT), "shared", "data")
OFF = ["--param", "object_gap=0", "--param", "min_object_voxels=0", "--param", "min_pocket_voxels=0",
       "--param", "surface_band=0", "--param", "structure_planes=0", "--param", "plane_holes=0"]
REAL = [("geb079.bt (native 8 cm)", "geb079.bt", []),
        ("office1.pcd at 2 cm", "office1.pcd", ["--voxel-size", "0.02"]),
        ("office1.pcd at 1 cm", "office1.pcd", ["--voxel-size", "0.01"]),
        ("table scene at 1 cm", "table_scene_mug_stereo_textured.pcd", ["--voxel-size", "0.01"]),
        ("table scene at 2 cm", "table_scene_mug_stereo_textured.pcd", ["--voxel-size", "0.02"])]
SCENES = ["cone", "cube", "cylinder", "close", "table", "doorway"]


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        sys.exit("failed (%d): %s\n%s" % (r.returncode, " ".join(cmd), r.stderr))
    return r.stdout


def table_columns(segments):
    """The issue's columns from a segments.json table."""
    occ = [s for s in segments if s["state"] == "occupied"]
    occ_vox = sum(s["voxels"] for s in occ)
    sizes = sorted((s["voxels"] for s in occ), reverse=True)
    held, k99 = 0, 0
    for v in sizes:
        if held >= 0.99 * occ_vox:
            break
        held += v
        k99 += 1
    kinds = {k: [s for s in segments if s.get("kind") == k] for k in ("structure", "object", "clutter")}
    so_vox = sum(s["voxels"] for s in kinds["structure"] + kinds["object"])
    return {
        "segments": len(segments),
        "occupied": len(occ),
        "occ<=8": sum(1 for s in occ if s["voxels"] <= 8),
        "occ99": k99,
        "fu<=8": sum(1 for s in segments if s["state"] != "occupied" and s["voxels"] <= 8),
        "structure": len(kinds["structure"]),
        "object": len(kinds["object"]),
        "clutter": len(kinds["clutter"]),
        "coverage": so_vox / occ_vox if occ_vox else 1.0,
        "clutter_share": sum(s["voxels"] for s in kinds["clutter"]) / occ_vox if occ_vox else 0.0,
    }


def segment(tool, path, extra, out, outputs="segments.json"):
    run([tool, "segment", path, "--out", out, "--quiet", "--outputs", outputs] + extra)
    with open(os.path.join(out, "segments.json")) as f:
        return json.load(f)["segments"]


def real(tool, work, before=OFF):
    print("| input | run | segments | occupied | occupied of <= 8 voxels | occupied segments holding 99 % "
          "| free/unknown of <= 8 voxels | structure / object / clutter | structure + object cover | clutter share |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, f, extra in REAL:
        for label, params in (("before", before), ("after", [])):
            c = table_columns(segment(tool, os.path.join(DATA, f), extra + params, os.path.join(work, "real")))
            print("| %s | %s | %d | %d | %d | %d | %d | %d / %d / %d | %.1f %% | %.2f %% |" % (
                name, label, c["segments"], c["occupied"], c["occ<=8"], c["occ99"], c["fu<=8"], c["structure"],
                c["object"], c["clutter"], 100 * c["coverage"], 100 * c["clutter_share"]))
        sys.stdout.flush()


def score(tool, truth, labels=None, segments=None, method=None):
    cmd = [tool, "evaluate", "--truth", truth, "--json"]
    if labels:
        cmd += ["--labels", labels, "--segments", segments]
    else:
        cmd += ["--method", method]
    return json.loads(run(cmd))["results"][0]["scores"]


def simulated(tool, work, dims, before=OFF, scenes=SCENES, reuse=False):
    print("| scene | method | segments | occupied segments per object | spanning | object voxels labelled free "
          "| IoU free / unknown / occupied | structure / object / clutter | free/unknown of <= 8 voxels |")
    print("|---|---|---|---|---|---|---|---|---|")
    for scene in scenes:
        truth = os.path.join(work, "sim-" + scene)
        if not (reuse and os.path.exists(os.path.join(truth, "scene.json"))):
            run([tool, "simulate", "--scene", scene, "--out", truth] + (["--dims"] + dims if dims else []))
        with open(os.path.join(truth, "scene.json")) as f:
            voxel = "%.17g" % json.load(f)["voxel_size"]
        rows = []
        for label, params in (("before", before), ("after", [])):
            out = os.path.join(work, "seg-" + scene + "-" + label)
            segs = segment(tool, os.path.join(truth, "map.npy"), ["--voxel-size", voxel] + params, out,
                           "labels.npy,segments.json")
            s = score(tool, truth, os.path.join(out, "labels.npy"), os.path.join(out, "segments.json"))
            rows.append((label, s, table_columns(segs)))
        rows.append(("baseline", score(tool, truth, method="baseline"), None))
        for label, s, c in rows:
            per = " / ".join(str(o["occupied_segments"]) for o in s["objects"])
            kinds = "%d / %d / %d" % (c["structure"], c["object"], c["clutter"]) if c else "-"
            fu = str(c["fu<=8"]) if c else "-"
            print("| %s | %s | %d | %s | %d | %.2f %% | %.3f / %.3f / %.3f | %s | %s |" % (
                scene, label, s["segments"], per, s["spanning_segments"], 100 * s["object_free_share"],
                s["iou"]["free"], s["iou"]["unknown"], s["iou"]["occupied"], kinds, fu))
        sys.stdout.flush()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--work")
    ap.add_argument("--real-only", action="store_true")
    ap.add_argument("--sim-only", action="store_true")
    ap.add_argument("--sim-dims", nargs=3)
    ap.add_argument("--scenes", help="simulated scenes, NAME,... (default: the six room scenes)")
    ap.add_argument("--reuse", action="store_true", help="keep simulations already in --work")
    ap.add_argument("--before", help="parameters of the 'before' run, NAME=VALUE,... (default: the object rules off)")
    a = ap.parse_args()
    before = OFF
    if a.before:
        before = []
        for kv in a.before.split(","):
            before += ["--param", kv]
    tool = os.path.join(a.build, "tools", "occseg")
    with tempfile.TemporaryDirectory() as tmp:
        work = a.work or tmp
        os.makedirs(work, exist_ok=True)
        if not a.sim_only:
            real(tool, work, before)
            print()
        if not a.real_only:
            simulated(tool, work, a.sim_dims, before, a.scenes.split(",") if a.scenes else SCENES, a.reuse)


if __name__ == "__main__":
    main()
