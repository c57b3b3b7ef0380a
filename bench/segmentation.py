# SPDX-License-Identifier: GPL-3.0-or-later
"""Segmentation benchmark: quality on the Princeton Segmentation Benchmark and speed against
CGAL's segmentation_from_sdf_values, our segment() and CGAL in one run on one machine.

    .venv/bin/python bench/segmentation.py PSB_FOLDER            # quality, then speed
    .venv/bin/python bench/segmentation.py PSB_FOLDER --quality  # the benchmark's measures only
    .venv/bin/python bench/segmentation.py PSB_FOLDER --speed    # the speed table only
    options: --only 1,81 (meshes by number)  --largest N (speed: skip meshes above N faces)
             --cgal PATH (default: $SDF_CGAL_SEGMENT, else build/cpp/tests/reference/cgal_segment)
             --no-cgal (with --quality: our variants only, where CGAL is not built)

PSB_FOLDER holds the meshes as off/N.off (or N.off) and the human segmentations as
seg/N/N_K.seg, as the benchmark distributes them: tests/data/psb (five meshes), or the
development subset unpacked (`tar -xJf psb-subset.tar.xz -C /tmp` gives /tmp/dev).

Quality: each mesh is segmented with the defaults (5 clusters, lambda 0.26) by
- CGAL: cgal_segment, CGAL's own sdf_values (25 rays, 120 degrees, post-processed) and
  segmentation_from_sdf_values;
- ours: shape_diameter.segment(vertices, triangles), the SDF computed with compute()'s defaults,
  mode "auto"; and again with mode="cgal"; and in mode "auto" with a minimum part size
  (min_part_area 0.5%, 1% and 2% of the area: "ours, min part 1%"); and asked for as many
  segments as the mesh's human segmentations have at the median ("ours, segments = people's
  median": what a user who knows how many parts they want gets);
- ours, mode="cgal" on CGAL's post-processed SDF: the same input as CGAL's segmentation, so its
  labels should equal CGAL's ("same labels" gives the share of faces that do), and its
  graph-cut energy CGAL's; the energies of CGAL's labels and of ours (both modes) on those
  values are tabled too.
Each is compared with every human segmentation of the mesh and the errors averaged over the
humans, then over a category's meshes, then over the categories, as the benchmark does
(measures in segmentation_measures.py: 1 - Rand index, cut discrepancy, Hamming distance,
GCE and LCE). "humans" compares each human segmentation with the mesh's other ones.

Speed: the SDF of a mesh is computed once (compute() with smoothing="kring", since a
segmentation wants a smoothed field) and rescaled linearly to [0, 1]; those same values go to
our segment() (values given, so no ray casting; best of 3 runs, wall and processor time of the
call) and to CGAL's segmentation_from_sdf_values (its own timers, one run), at about 20k,
100k, 500k, 830k and 1.2M faces (repository meshes, the larger ones made by 1-to-4
subdivision as in meshes.py). The ratio is CGAL's time over ours. CGAL's segmentation runs on
one thread, so its processor time is its wall time on an idle machine: on a busy machine
compare the processor times too (ours counts every thread's).
"""

from __future__ import annotations

import argparse
import datetime
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import shape_diameter as sd
from meshes import CACHE, DATA, ROOT, read_off, subdivide, write_off
from segmentation_measures import MeshCuts, consistency, hamming, rand_error

from bench import machine_line

sys.path.insert(0, str(ROOT / "tests" / "python"))
import cgal_segment_reference as cgal_ref  # noqa: E402  (reads cgal_segment's output)

# The benchmark's categories: meshes 20 * i + 1 .. 20 * i + 20 (261-280 are not used).
CATEGORIES = {
    1: "human",
    21: "cup",
    41: "glasses",
    61: "airplane",
    81: "ant",
    101: "chair",
    121: "octopus",
    141: "table",
    161: "teddy",
    181: "hand",
    201: "plier",
    221: "fish",
    241: "bird",
    281: "armadillo",
    301: "bust",
    321: "mech",
    341: "bearing",
    361: "vase",
    381: "fourleg",
}
MEASURES = ("1-RI", "CD", "HD", "GCE", "LCE")
# The minimum part sizes tried beside the default (segment(min_part_area=...), shares of the
# mesh's area).
MIN_PART_AREAS = (0.005, 0.01, 0.02)
HAVE_SEGMENT = hasattr(sd, "segment")
if HAVE_SEGMENT:
    from shape_diameter.segmentation import segmentation_energy


def category(number: int) -> str:
    return CATEGORIES.get((number - 1) // 20 * 20 + 1, "other")


def cgal_binary(given: str) -> str:
    path = (
        given
        or os.environ.get("SDF_CGAL_SEGMENT", "")
        or str(ROOT / "build" / "cpp" / "tests" / "reference" / "cgal_segment")
    )
    if not os.access(path, os.X_OK):
        sys.exit(
            f"cgal_segment not found at {path}: build tests/reference (needs libcgal-dev) "
            "or pass --cgal"
        )
    return path


def psb_meshes(folder: Path, only: set[int]) -> list[tuple[int, Path, list[Path]]]:
    """[(number, OFF path, its human segmentation files)], by number."""
    off_dir = folder / "off" if (folder / "off").is_dir() else folder
    found = []
    for off in off_dir.glob("*.off"):
        if not off.stem.isdigit() or (only and int(off.stem) not in only):
            continue
        humans = sorted((folder / "seg" / off.stem).glob(f"{off.stem}_*.seg"))
        if humans:
            found.append((int(off.stem), off, humans))
    if not found:
        sys.exit(f"{folder}: no N.off with seg/N/N_K.seg found")
    return sorted(found)


# --------------------------------------------------------------------------- quality


def _mean(rows: list) -> np.ndarray:
    """Column means that skip nan, nan where a column has no number."""
    table = np.asarray(rows, dtype=np.float64).reshape(len(rows), -1)
    counts = np.isfinite(table).sum(axis=0)
    sums = np.where(np.isfinite(table), table, 0.0).sum(axis=0)
    return np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)


def scores(cuts: MeshCuts, labels: np.ndarray, humans: list, human_cuts: list) -> np.ndarray:
    """The measures of one segmentation against each human one, averaged over the humans."""
    own_cuts = cuts.distance_to_cuts(labels)
    rows = []
    for human, distance in zip(humans, human_cuts):
        gce, lce = consistency(labels, human)
        rows.append(
            (
                rand_error(labels, human),
                cuts.cut_discrepancy(labels, human, own_cuts, distance),
                hamming(labels, human)[0],
                gce,
                lce,
            )
        )
    return _mean(rows)


def segmentations(off: Path, vertices, triangles, cgal: str, tmp: Path, wanted: int) -> dict:
    """{method: labels} for one mesh, and 'same labels' for the run on CGAL's SDF; `wanted`:
    the segment count to ask for (the people's median)."""
    out = {}
    ref = cgal_ref.run(off, tmp / "cgal.txt") if cgal else None
    if ref is not None:
        out["CGAL"] = ref.labels
    if not HAVE_SEGMENT:
        return out
    # One SDF for every variant: segment(values=None) computes it the same way (compute()'s
    # defaults, then CGAL's post-processing filter).
    values = sd.compute(vertices, triangles).values
    variants = [("ours", {}), ('ours, mode="cgal"', {"mode": "cgal"})]
    variants += [(f"ours, min part {100 * s:g}%", {"min_part_area": s}) for s in MIN_PART_AREAS]
    variants.append(("ours, segments = people's median", {"segments": wanted}))
    for name, kwargs in variants:
        seg = sd.segment(vertices, triangles, values, postprocess=True, **kwargs)
        out[name] = np.asarray(seg.labels)
    if ref is not None:
        same = sd.segment(vertices, triangles, ref.sdf, mode="cgal")
        out['ours, mode="cgal", CGAL\'s SDF'] = np.asarray(same.labels)
        out["same labels"] = float(np.mean(np.asarray(same.labels) == ref.labels))
        auto = sd.segment(vertices, triangles, ref.sdf)
        out["energy"] = (
            segmentation_energy(vertices, triangles, ref.sdf, ref.clusters),
            same.energy,
            auto.energy,
        )
    return out


def quality_of_mesh(number: int, off: Path, human_files: list, cgal: str, tmp: Path) -> dict:
    vertices, triangles = read_off(off)
    humans = [np.loadtxt(h, dtype=np.int64, ndmin=1) for h in human_files]
    for path, human in zip(human_files, humans):
        if len(human) != len(triangles):
            sys.exit(f"{path}: {len(human)} labels for {len(triangles)} faces")
    cuts = MeshCuts(vertices, triangles)
    human_cuts = [cuts.distance_to_cuts(h) for h in humans]
    wanted = round(float(np.median([len(np.unique(h)) for h in humans])))
    found = segmentations(off, vertices, triangles, cgal, tmp, wanted)
    row = {
        "mesh": number,
        "category": category(number),
        "faces": len(triangles),
        "humans": len(humans),
        "same labels": found.pop("same labels", None),
        "energy": found.pop("energy", None),
        "methods": {},
    }
    for method, labels in found.items():
        row["methods"][method] = dict(
            zip(MEASURES, scores(cuts, labels, humans, human_cuts)), segments=len(np.unique(labels))
        )
    others = []
    for i in range(len(humans)):
        rest = [j for j in range(len(humans)) if j != i]
        others.append(
            scores(cuts, humans[i], [humans[j] for j in rest], [human_cuts[j] for j in rest])
        )
    row["methods"]["humans"] = dict(
        zip(MEASURES, _mean(others)), segments=float(np.mean([len(np.unique(h)) for h in humans]))
    )
    return row


def quality_tables(rows: list) -> list[str]:
    methods = list(rows[0]["methods"])
    lines = [
        "Per mesh: 1 - Rand index (segments)",
        "",
        "| mesh | category | faces | humans | " + " | ".join(methods) + " | same labels |",
        "|---:|---|---:|---:|" + "---:|" * (len(methods) + 1),
    ]
    for r in rows:
        cells = [
            f"{r['methods'][m]['1-RI']:.3f} ({r['methods'][m]['segments']:.0f})" for m in methods
        ]
        same = (
            ""
            if r["same labels"] is None
            else (
                f"{100 * r['same labels']:.2f}% ({round((1 - r['same labels']) * r['faces'])} "
                "differ)"
            )
        )
        lines.append(
            f"| {r['mesh']} | {r['category']} | {r['faces']:,} | {r['humans']} | "
            + " | ".join(cells)
            + f" | {same} |"
        )
    if rows[0]["energy"] is not None:
        lines += [
            "",
            "Graph-cut energy of the labels on CGAL's SDF (CGAL's probabilities and edge weights)",
            "",
            '| mesh | CGAL | ours, mode="cgal" | ours (auto) | auto / CGAL |',
            "|---:|---:|---:|---:|---:|",
        ]
        lines += [
            f"| {r['mesh']} | {r['energy'][0]:.6g} | {r['energy'][1]:.6g} | "
            f"{r['energy'][2]:.6g} | {r['energy'][2] / r['energy'][0]:.4f} |"
            for r in rows
        ]
    by_category = {}
    for r in rows:
        by_category.setdefault(r["category"], []).append(r)
    lines += [
        "",
        "Per category: 1 - Rand index",
        "",
        "| category | meshes | " + " | ".join(methods) + " |",
        "|---|---:|" + "---:|" * len(methods),
    ]
    category_means = {}
    for name, members in by_category.items():
        category_means[name] = {
            m: _mean([[r["methods"][m][k] for k in MEASURES] for r in members]) for m in methods
        }
        lines.append(
            f"| {name} | {len(members)} | "
            + " | ".join(f"{category_means[name][m][0]:.3f}" for m in methods)
            + " |"
        )
    lines += [
        "",
        f"Overall (mean over {len(category_means)} categories; cut discrepancy: "
        "shortest paths along edges)",
        "",
        "| method | " + " | ".join(MEASURES) + " |",
        "|---|" + "---:|" * len(MEASURES),
    ]
    for m in methods:
        overall = _mean([category_means[c][m] for c in category_means])
        lines.append(f"| {m} | " + " | ".join(f"{v:.3f}" for v in overall) + " |")
    return lines


# --------------------------------------------------------------------------- speed


def speed_meshes(largest: int) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """Repository meshes of about 20k, 100k, 500k, 830k and 1.2M faces."""
    plan = [
        ("ChineseDragon-10kv", DATA / "ChineseDragon-10kv.off", 0),
        ("psb-241-x16", DATA / "psb" / "241.off", 2),
        ("psb-241-x64", DATA / "psb" / "241.off", 3),
        ("armadillo-x16", DATA / "armadillo.off", 2),
        ("bunny00-x16", DATA / "bunny00.off", 2),
    ]
    CACHE.mkdir(parents=True, exist_ok=True)
    meshes = []
    for name, source, times in plan:
        cached = CACHE / f"{name}.npz"
        if cached.exists():
            z = np.load(cached)
            vertices, triangles = z["vertices"], z["triangles"]
        else:
            vertices, triangles = read_off(source)
            for _ in range(times):
                vertices, triangles = subdivide(vertices, triangles)
            np.savez(cached, vertices=vertices, triangles=triangles)
        if len(triangles) <= largest:
            meshes.append((name, vertices, triangles))
    return meshes


def speed_of_mesh(name, vertices, triangles, cgal: str, tmp: Path) -> dict:
    off = tmp / f"{name}.off"
    write_off(off, vertices, triangles)
    start = time.perf_counter()
    sdf = sd.compute(vertices, triangles, smoothing="kring")
    sdf_seconds = time.perf_counter() - start
    values = np.asarray(sdf.values, dtype=np.float64)
    values = (values - values.min()) / max(values.max() - values.min(), 1e-300)
    ref = cgal_ref.run(off, tmp / f"{name}.txt", values=values)
    row = {
        "mesh": name,
        "faces": len(triangles),
        "sdf": sdf_seconds,
        "CGAL": (ref.header["segmentation_seconds"], ref.header["segmentation_cpu_seconds"]),
        "segments CGAL": ref.header["segments"],
    }
    if not HAVE_SEGMENT:
        return row
    for mode in ("auto", "cgal"):
        best = None
        for _ in range(3):
            wall, cpu = time.perf_counter(), time.process_time()
            result = sd.segment(vertices, triangles, values, mode=mode)
            times = (time.perf_counter() - wall, time.process_time() - cpu)
            best = times if best is None or times[0] < best[0] else best
        row[mode] = best
        row[f"segments {mode}"] = int(result.segment_count)
        if mode == "cgal":
            row["same labels"] = float(np.mean(np.asarray(result.labels) == ref.labels))
    return row


def speed_table(rows: list) -> list[str]:
    lines = [
        "Speed: segmentation from the same SDF values, seconds of wall time (processor time "
        "in brackets; ratio = CGAL / ours, wall and processor)",
        "",
        "| mesh | faces | our SDF | CGAL | ours (auto) | ratio | ours (mode=cgal) | ratio | "
        "segments CGAL / cgal / auto | same labels |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---|---:|",
    ]

    def pair(t):
        return f"{t[0]:.3f} ({t[1]:.3f})"

    def ratio(a, b):
        return f"{a[0] / b[0]:.1f}x ({a[1] / max(b[1], 1e-9):.1f}x)"

    for r in rows:
        cgal = r["CGAL"]
        if "auto" in r:
            ours = (
                f"{pair(r['auto'])} | {ratio(cgal, r['auto'])} | {pair(r['cgal'])} | "
                f"{ratio(cgal, r['cgal'])} | {r['segments CGAL']} / {r['segments cgal']} / "
                f"{r['segments auto']} | {100 * r['same labels']:.2f}% "
                f"({round((1 - r['same labels']) * r['faces'])} differ)"
            )
        else:
            ours = f"- | - | - | - | {r['segments CGAL']} / - / - | -"
        lines.append(f"| {r['mesh']} | {r['faces']:,} | {r['sdf']:.2f} | {pair(cgal)} | {ours} |")
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("psb", type=Path, help="folder with off/N.off and seg/N/N_K.seg")
    parser.add_argument("--quality", action="store_true", help="only the benchmark's measures")
    parser.add_argument("--speed", action="store_true", help="only the speed table")
    parser.add_argument("--only", default="", help="comma-separated mesh numbers (quality)")
    parser.add_argument(
        "--largest", type=int, default=2_000_000, help="speed: skip meshes above this many faces"
    )
    parser.add_argument("--cgal", default="", help="path of the cgal_segment reference")
    parser.add_argument(
        "--no-cgal", action="store_true", help="quality of our variants only, without CGAL"
    )
    args = parser.parse_args()
    folder = args.psb / "dev" if (args.psb / "dev").is_dir() else args.psb
    if args.no_cgal and not args.quality:
        sys.exit("--no-cgal measures quality only (the speed table is against CGAL): add --quality")
    cgal = "" if args.no_cgal else cgal_binary(args.cgal)
    os.environ["SDF_CGAL_SEGMENT"] = cgal
    tmp = Path(tempfile.mkdtemp(prefix="sdf-segmentation-"))
    print(
        f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, "
        f"{machine_line()}, load average {os.getloadavg()[0]:.1f} at the start, "
        f"shape_diameter {sd.__version__}"
    )
    if not HAVE_SEGMENT:
        print("shape_diameter.segment is not in this build: CGAL's half only")
    if not args.speed:
        only = {int(n) for n in args.only.split(",") if n}
        rows = []
        for number, off, humans in psb_meshes(folder, only):
            rows.append(quality_of_mesh(number, off, humans, cgal, tmp))
            print(
                f"  mesh {number}: "
                + ", ".join(f"{m} {v['1-RI']:.3f}" for m, v in rows[-1]["methods"].items()),
                flush=True,
            )
        print("\n".join(["", *quality_tables(rows), ""]))
    if not args.quality:
        rows = []
        for name, vertices, triangles in speed_meshes(args.largest):
            rows.append(speed_of_mesh(name, vertices, triangles, cgal, tmp))
            print(f"  {name}: CGAL {rows[-1]['CGAL'][0]:.3f} s", flush=True)
        print("\n".join(["", *speed_table(rows)]))


if __name__ == "__main__":
    main()
