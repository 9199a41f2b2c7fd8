#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""How the cloth collision step's cost grows with the mesh: reads impact-cloth-bench --json files
of one scene at several sizes (repeats of a size are shown as a range), prints a Markdown table
(vertices, collision CPU ms per step: mean over all steps and over the contact steps, and per 1,000
vertices) and draws it log-log with a line of slope 1 (linear cost) through the smallest size.
Needs Debian's python3-matplotlib; not needed by the tests.

    /usr/bin/python3 benches/plot_cloth_scaling.py OUT.png RUN.json... [--contact-from STEP]
                                                   [--title TEXT]"""
import argparse
import json
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("png")
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--contact-from", type=int, default=13, help="first step of the contact steps' mean")
    ap.add_argument("--title", default="")
    a = ap.parse_args()

    by_size = defaultdict(lambda: {"all": [], "contact": [], "candidates": []})
    last = 0
    for path in a.runs:
        with open(path) as f:
            d = json.load(f)
        cpu = [r["collision_cpu_ms"] for r in d["rows"]]
        last = max(last, len(cpu) - 1)
        contact = cpu[a.contact_from:]
        s = by_size[d["vertices"]]
        s["all"].append(sum(cpu) / len(cpu))
        s["contact"].append(sum(contact) / len(contact) if contact else float("nan"))
        s["candidates"].append(d["rows"][-1]["candidates"])

    def rng(xs, scale=1.0, fmt="{:,.1f}"):
        lo, hi = min(xs) * scale, max(xs) * scale
        return fmt.format(lo) if fmt.format(lo) == fmt.format(hi) else fmt.format(lo) + "–" + fmt.format(hi)

    sizes = sorted(by_size)
    contact_label = f"mean of steps {a.contact_from}–{last}"
    print(f"| vertices | collision ms/step, mean of all steps | per 1,000 vertices | {contact_label} | per 1,000 vertices | candidates per vertex (last step) |")
    print("|---:|---:|---:|---:|---:|---:|")
    for n in sizes:
        s = by_size[n]
        print(f"| {n:,} | {rng(s['all'])} | {rng(s['all'], 1e3 / n, '{:,.2f}')} | {rng(s['contact'])} | "
              f"{rng(s['contact'], 1e3 / n, '{:,.2f}')} | {rng(s['candidates'], 1.0 / n)} |")

    fig, ax = plt.subplots(figsize=(4.6, 3.4), dpi=90)
    for key, label, colour in (("all", "mean of all steps", "tab:blue"), ("contact", contact_label, "tab:red")):
        mid = [sum(by_size[n][key]) / len(by_size[n][key]) for n in sizes]
        lo = [mid[i] - min(by_size[n][key]) for i, n in enumerate(sizes)]
        hi = [max(by_size[n][key]) - mid[i] for i, n in enumerate(sizes)]
        ax.errorbar(sizes, mid, yerr=[lo, hi], marker="o", ms=4, capsize=2, color=colour, label=label)
        ax.plot([sizes[0], sizes[-1]], [mid[0], mid[0] * sizes[-1] / sizes[0]], ls=":", color=colour, lw=1)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("cloth vertices")
    ax.set_ylabel("collision CPU ms per step")
    ax.set_title(a.title or "cloth collision step: cost against size (dotted: linear)", fontsize=8)
    ax.legend(fontsize=7)
    ax.grid(True, which="both", lw=0.3)
    fig.tight_layout()
    fig.savefig(a.png)


if __name__ == "__main__":
    main()
