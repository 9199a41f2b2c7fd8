#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Turns the --json output of impact's benches into PNG charts.

    python3 benches/plot.py RUN.json [RUN.json ...] [-o OUTDIR] [--name STEM]

Each file is recognised by its content, so several runs of the same bench can be given together:
the charts then show the median of the runs with a bar from the lowest to the highest value (the
ranges the docs quote). Charts written, when the JSON holds the data:

  impact-scene-bench     <stem>-scene-scaling.png   ms per step against objects, per method
                         <stem>-scene-methods.png   ms per step per method (main scene)
                         <stem>-scene-threads.png   ms per step against threads (rows with "threads")
  impact-collide-bench   <stem>-collide.png         median µs per method, boolean and all-pairs
  impact-ccd-bench       <stem>-ccd-sweep.png       mean µs and false positives against tolerance
  impact-fit-bench       <stem>-fit.png             time against radius excess per fitting method
  impact-particles-bench <stem>-particles.png       particle-steps/s against position error
  a ray bench            <stem>-rays.png            rays per second per set and library
  any rows with "threads" and a time or rate: <stem>-threads.png

Needs matplotlib (Debian python3-matplotlib); the test suite never runs it.
"""
import argparse
import json
import os
import statistics
import sys
from collections import defaultdict

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:  # pragma: no cover - reported to the user
    sys.exit("plot.py needs matplotlib (Debian: apt-get install python3-matplotlib)")

FIGSIZE = (6.4, 3.6)
DPI = 100


def spread(values):
    """Median and the distances to the lowest and highest value (for error bars)."""
    m = statistics.median(values)
    return m, m - min(values), max(values) - m


def save(fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=DPI, pil_kwargs={"optimize": True})
    plt.close(fig)
    print(f"wrote {path} ({os.path.getsize(path) // 1024} KB)")


def error_bars(stats, scale=1):
    """The bar heights and the (low, high) error bars of spread() results, divided by scale."""
    return [st[0] / scale for st in stats], [[st[1] / scale for st in stats], [st[2] / scale for st in stats]]


def plot_series(ax, series, labels):
    """One line with error bars per name of series ({name: {x: [values]}}), x sorted."""
    for name, pts in series.items():
        xs = sorted(pts)
        ys, yerr = error_bars([spread(pts[x]) for x in xs])
        ax.errorbar(xs, ys, yerr=yerr, marker="o", ms=3, capsize=2, label=labels.get(name, name))


def grouped_bars(ax, per, groups, members, label=str, scale=1):
    """Bars of per[(group, member)] (spread of the values, divided by scale; 0 where missing): one
    cluster per group, with its x tick in the middle, one bar per member (legend: label(member))."""
    width = 0.8 / max(len(members), 1)
    for mi, member in enumerate(members):
        ys, yerr = error_bars([spread(per[(g, member)]) if (g, member) in per else (0, 0, 0) for g in groups], scale)
        ax.bar([i + mi * width for i in range(len(groups))], ys, width, yerr=yerr, capsize=2, label=label(member))
    ax.set_xticks([i + width * (len(members) - 1) / 2 for i in range(len(groups))])


def finish(fig, out, stem, suffix):
    """Saves the chart as <out>/<stem>-<suffix>.png and returns its path."""
    path = os.path.join(out, f"{stem}-{suffix}.png")
    save(fig, path)
    return path


def rows_of(doc):
    for key in ("rows", "results"):
        if isinstance(doc.get(key), list):
            return doc[key]
    return []


def kind_of(doc):
    bench = doc.get("bench", "")
    if bench:
        return bench
    if "sweep" in doc or "totals" in doc:
        return "impact-ccd-bench"
    rows = rows_of(doc)
    if rows and "rays_per_s" in rows[0]:
        return "impact-ray-bench"
    if rows and "whole_radius_excess" in rows[0]:
        return "impact-fit-bench"
    if rows and "library" in rows[0] and "median_us" in rows[0]:
        return "impact-collide-bench"
    if rows and "particle_steps_per_s" in rows[0]:
        return "impact-particles-bench"
    if "scaling" in doc:
        return "impact-scene-bench"
    return "unknown"


# --- impact-scene-bench --------------------------------------------------------------------------
SCENE_LABELS = {
    "impact-all-pairs": "impact all-pairs",
    "impact-static-dynamic": "impact static/dynamic",
    "impact-hierarchical": "impact hierarchical",
    "fcl-dynamic-aabb-tree": "FCL dynamic AABB tree (2 managers)",
    "bullet-dbvt-defaults": "Bullet btDbvt, defaults",
    "bullet-dbvt-tuned": "Bullet btDbvt, tuned",
}


def plot_scene(docs, out, stem):
    written = []
    # scaling with objects
    series = defaultdict(lambda: defaultdict(list))
    for d in docs:
        for r in d.get("scaling", []):
            if r.get("ms_per_step", 0) > 0 and r.get("threads", 1) == 1:
                series[r["method"]][r["objects"]].append(r["ms_per_step"])
    if series:
        fig, ax = plt.subplots(figsize=FIGSIZE)
        plot_series(ax, series, SCENE_LABELS)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("objects (10 % dynamic)")
        ax.set_ylabel("ms per step (one thread, CPU time)")
        ax.set_title("Broad phase: time per step against scene size")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
        written.append(finish(fig, out, stem, "scene-scaling"))
    # main scene, per method
    per = defaultdict(list)
    for d in docs:
        frac = d.get("dynamic_fraction")
        for r in d.get("rows", []):
            if r.get("dynamic_fraction") == frac and r.get("threads", 1) == 1:
                per[r["method"]].append(r["ms_per_step"])
    if per:
        fig, ax = plt.subplots(figsize=FIGSIZE)
        methods = list(per)
        stats = [spread(per[m]) for m in methods]
        y = range(len(methods))
        xs, xerr = error_bars(stats)
        ax.barh(y, xs, xerr=xerr, capsize=3,
                color=["#1f77b4" if m.startswith("impact") else "#999999" for m in methods])
        ax.set_yticks(list(y))
        ax.set_yticklabels([SCENE_LABELS.get(m, m) for m in methods], fontsize=8)
        ax.invert_yaxis()
        ax.set_xlabel("ms per step (one thread, CPU time; lower is better)")
        d0 = docs[0]
        ax.set_title(f"{d0.get('objects', '?'):,} objects, {100 * d0.get('dynamic_fraction', 0):.0f} % dynamic"
                     f" ({len(docs)} run{'s' if len(docs) > 1 else ''})")
        for i, s in enumerate(stats):
            ax.text(s[0] + s[2], i, f" {s[0]:.1f}", va="center", fontsize=7)
        ax.grid(True, axis="x", alpha=0.3)
        written.append(finish(fig, out, stem, "scene-methods"))
    written += plot_threads(docs, out, stem + "-scene", "ms_per_step", "ms per step")
    return written


def plot_threads(docs, out, stem, key=None, label=None):
    """Any rows carrying "threads": time or rate against the thread count, per method."""
    series = defaultdict(lambda: defaultdict(list))
    for d in docs:
        for r in rows_of(d):
            if "threads" not in r:
                continue
            # the scene bench's main scene only (not its all-static rows)
            if "dynamic_fraction" in r and "dynamic_fraction" in d and r["dynamic_fraction"] != d["dynamic_fraction"]:
                continue
            k = key if key and key in r else next((c for c in ("ms_per_step", "rays_per_s", "particle_steps_per_s",
                                                               "mean_us", "median_us") if c in r), None)
            if k is None:
                continue
            label = label or k
            name = r.get("method") or r.get("library") or "?"
            series[name][r["threads"]].append(r[k])
    if not any(len(v) > 1 for v in series.values()):
        return []
    fig, ax = plt.subplots(figsize=FIGSIZE)
    plot_series(ax, series, SCENE_LABELS)
    ax.set_xlabel("threads")
    ax.set_ylabel(label)
    ax.set_title("Scaling with threads")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return [finish(fig, out, stem, "threads")]


# --- impact-collide-bench ------------------------------------------------------------------------
def plot_collide(docs, out, stem):
    per = defaultdict(list)
    for d in docs:
        for r in rows_of(d):
            per[((r["library"], r["bv"]), r["query"])].append(r["median_us"])
    if not per:
        return []
    methods = sorted({m for m, _ in per}, key=lambda m: (m[0] != "fcl", m))
    queries = [q for q in ("boolean", "all_pairs") if any(k[1] == q for k in per)]
    fig, ax = plt.subplots(figsize=FIGSIZE)
    grouped_bars(ax, per, methods, queries, label=lambda q: q.replace("_", "-"))
    ax.set_xticklabels([f"{lib} {bv}" for lib, bv in methods], fontsize=8)
    ax.set_ylabel("median µs per query (lower is better)")
    d0 = docs[0]
    a = os.path.basename(str(d0.get("mesh_a", "?")))
    b = os.path.basename(str(d0.get("mesh_b", "?")))
    ax.set_title(f"Mesh–mesh collision: {a} / {b}, {d0.get('poses', '?')} poses ({len(docs)} runs)")
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    return [finish(fig, out, stem, "collide")]


# --- time against error --------------------------------------------------------------------------
def plot_ccd(docs, out, stem):
    """Time and false positives against the tolerance (the sweep points at the default separation
    and re-check budget), vertex-face and edge-edge."""
    pts = defaultdict(list)  # (kind, tol, d, recheck) -> [(fp rate, mean us)]
    for d in docs:
        for s in d.get("sweep", []):
            r = s.get("row", s)
            pts[(r.get("kind", "?"), s.get("tolerance"), s.get("min_separation"), s.get("recheck_iterations"))].append(
                (r.get("false_positives", 0) / max(r.get("queries", 1), 1), r.get("mean_us", 0)))
    if not pts:
        return []
    default_recheck = docs[0].get("recheck_iterations")
    fig, (ax_t, ax_e) = plt.subplots(1, 2, figsize=(FIGSIZE[0] * 1.3, FIGSIZE[1]))
    for kind, marker in (("vertex-face", "o"), ("edge-edge", "s")):
        sel = sorted((k[1], v) for k, v in pts.items() if k[0] == kind and k[2] == 0 and k[3] == default_recheck)
        if not sel:
            continue
        tols = [t for t, _ in sel]
        ax_t.plot(tols, [statistics.median(p[1] for p in v) for _, v in sel], marker=marker, ms=4, label=kind)
        ax_e.plot(tols, [statistics.median(p[0] for p in v) for _, v in sel], marker=marker, ms=4, label=kind)
    for ax in (ax_t, ax_e):
        ax.set_xscale("log")
        ax.set_xlabel("tolerance")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    ax_t.set_ylabel("mean µs per query")
    ax_e.set_ylabel("false-positive rate")
    ax_e.set_yscale("symlog", linthresh=1e-4)
    ax_e.set_ylim(bottom=0)
    ax_t.set_title("CCD: time against tolerance", fontsize=10)
    ax_e.set_title("CCD: false positives against tolerance", fontsize=10)
    return [finish(fig, out, stem, "ccd-sweep")]


def plot_fit(docs, out, stem):
    pts = defaultdict(list)
    for d in docs:
        for r in rows_of(d):
            pts[(os.path.basename(r.get("mesh", "?")), r["method"])].append((r["tree_build_ms"], r["tree_radius_sum_excess"]))
    if not pts:
        return []
    fig, ax = plt.subplots(figsize=FIGSIZE)
    for (mesh, method), v in pts.items():
        x = statistics.median(p[0] for p in v)
        y = statistics.median(p[1] for p in v)
        ax.scatter([x], [100 * y], s=20)
        ax.annotate(f"{method} ({mesh})", (x, 100 * y), fontsize=6, xytext=(3, 2), textcoords="offset points")
    ax.set_xlabel("tree build ms")
    ax.set_ylabel("summed radius excess over exact, %")
    ax.set_title("Sphere fitting: build time against tightness")
    ax.grid(True, alpha=0.3)
    return [finish(fig, out, stem, "fit")]


def plot_particles(docs, out, stem):
    pts = defaultdict(list)
    for d in docs:
        for r in rows_of(d):
            pts[r["method"]].append((r["particle_steps_per_s"], r.get("pos_err_mean", 0)))
    if not pts:
        return []
    fig, ax = plt.subplots(figsize=FIGSIZE)
    for method, v in pts.items():
        xs = [p[1] for p in v]
        ys = [p[0] for p in v]
        ax.scatter(xs, ys, s=18, label=method)
    ax.set_xscale("symlog", linthresh=1e-6)
    ax.set_yscale("log")
    ax.set_xlabel("mean position error against the sub-stepped reference")
    ax.set_ylabel("particle-steps per second")
    ax.set_title("Particles: speed against error")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return [finish(fig, out, stem, "particles")] + plot_threads(docs, out, stem + "-particles")


def plot_rays(docs, out, stem):
    per = defaultdict(list)
    for d in docs:
        for r in rows_of(d):
            if "threads" in r and r["threads"] != 1:
                continue
            name = f"{r.get('library', '?')} {r.get('method', '')}".strip()
            per[(r.get("set", "?"), name)].append(r["rays_per_s"])
    if not per:
        return []
    sets = sorted({k[0] for k in per})
    names = sorted({k[1] for k in per})
    fig, ax = plt.subplots(figsize=FIGSIZE)
    grouped_bars(ax, per, sets, names, scale=1e6)
    ax.set_xticklabels(sets)
    ax.set_ylabel("million rays per second (one thread)")
    ax.set_title("Ray casts per set and library")
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=7)
    return [finish(fig, out, stem, "rays")] + plot_threads(docs, out, stem + "-rays")


PLOTTERS = {
    "impact-scene-bench": plot_scene,
    "impact-collide-bench": plot_collide,
    "impact-ccd-bench": plot_ccd,
    "impact-fit-bench": plot_fit,
    "impact-particles-bench": plot_particles,
    "impact-ray-bench": plot_rays,
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("json", nargs="+", help="--json output of one or more bench runs")
    ap.add_argument("-o", "--out", default=".", help="folder for the PNG files (default: here)")
    ap.add_argument("--name", help="file name stem (default: the first JSON file's name)")
    args = ap.parse_args(argv)
    groups = defaultdict(list)
    for path in args.json:
        with open(path, encoding="utf-8") as f:
            try:
                doc = json.load(f)
            except json.JSONDecodeError as e:
                sys.exit(f"{path}: not JSON ({e})")
        groups[kind_of(doc)].append((path, doc))
    os.makedirs(args.out, exist_ok=True)
    written = []
    for kind, items in groups.items():
        stem = args.name or os.path.splitext(os.path.basename(items[0][0]))[0]
        plotter = PLOTTERS.get(kind)
        docs = [d for _, d in items]
        if plotter is None:
            written += plot_threads(docs, args.out, stem)
            if not written:
                print(f"{items[0][0]}: no chart for this JSON", file=sys.stderr)
            continue
        written += plotter(docs, args.out, stem)
    if not written:
        sys.exit("no chart written")


if __name__ == "__main__":
    main()
