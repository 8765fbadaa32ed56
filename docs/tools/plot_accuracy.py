#!/usr/bin/env python3
"""Error against cost (Pareto view) from `hemo-bench accuracy --json` files.

usage: plot_accuracy.py OUT_DIR BENCH.json [BENCH.json ...]
Writes OUT_DIR/accuracy_<case>.png: error (y) against wall seconds per simulated second (x),
one marker series per pressure solver (wcsph, dfsph), integrator, density method and smoothing ratio
h/dp, each point labelled with its particle spacing.
Needs matplotlib (Debian: python3-matplotlib); only for docs, not for building hemo.
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    out = sys.argv[1]
    rows = []
    devices = []
    for path in sys.argv[2:]:
        with open(path) as f:
            bench = json.load(f)
        rows += bench["rows"]
        devices.append(bench.get("device", "unknown device"))
    for case in sorted({r["case"] for r in rows}):
        fig, ax = plt.subplots(figsize=(9, 4.2))
        ratios = sorted({r.get("smoothing_ratio", 1.3) for r in rows if r["case"] == case}, reverse=True)
        series = (("wcsph", "symplectic_euler", "summation", "o"), ("wcsph", "rk2_midpoint", "summation", "s"),
                  ("wcsph", "symplectic_euler", "continuity", "^"), ("wcsph", "rk2_midpoint", "continuity", "v"),
                  ("dfsph", "symplectic_euler", "summation", "D"))
        for solver, integrator, density, marker in series:
            for ratio in ratios:
                pts = sorted((r["wall_s_per_sim_s"], r["error"], r["spacing_m"]) for r in rows
                             if r["case"] == case and r["integrator"] == integrator
                             and r.get("solver", "wcsph") == solver
                             and r.get("density", "summation") == density
                             and abs(r.get("smoothing_ratio", 1.3) - ratio) < 1e-3)
                if not pts:
                    continue
                label = (f"{solver}, {integrator}, h/dp = {ratio:.2f}" +
                         (", continuity density" if density == "continuity" else ""))
                ax.plot([p[0] for p in pts], [p[1] for p in pts], marker=marker, label=label)
                for x, y, dp in pts:
                    ax.annotate(f"dp={dp * 1000:.3g} mm", (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7)
        metric = next(r["error_metric"] for r in rows if r["case"] == case)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(f"wall seconds per simulated second ({', '.join(sorted(set(devices)))})")
        ax.set_ylabel(metric)
        ax.set_title(f"{case}: error against cost")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
        fig.tight_layout()
        fig.savefig(f"{out}/accuracy_{case}.png", dpi=110)


if __name__ == "__main__":
    main()
