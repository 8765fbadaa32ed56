#!/usr/bin/env python3
"""GPU time of the blood surface against grid size from `hemo-bench render --json` files.

usage: plot_render.py OUT.png BENCH.json
One panel per scene: side by side at each grid (64^3, 128^3, 256^3), the GPU ms of the field,
the extraction and the draw, and the CPU reference marching cubes on the same field; the
20 ms extraction goal as a line (log scale). Needs matplotlib (Debian: python3-matplotlib); only for docs.
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    with open(sys.argv[2]) as f:
        bench = json.load(f)
    rows = bench["rows"]
    device = bench.get("device", "unknown device")
    scenes = sorted({r["scene"] for r in rows})
    fig, axes = plt.subplots(1, len(scenes), figsize=(5.2 * len(scenes), 4.2), sharey=True)
    if len(scenes) == 1:
        axes = [axes]
    for ax, scene in zip(axes, scenes):
        sel = sorted((r for r in rows if r["scene"] == scene), key=lambda r: r["grid"])
        x = list(range(len(sel)))
        series = [("field (splat + upsample)", [r["gpu_field_ms"] for r in sel], "#8c2d04"),
                  ("extraction, GPU", [r["gpu_extract_ms"] for r in sel], "#d94801"),
                  ("extraction, CPU reference", [r["cpu_ms"] for r in sel], "#636363"),
                  ("draw 960x540", [r["draw_ms"] or 0.0 for r in sel], "#fdae6b")]
        width = 0.2
        for k, (label, values, color) in enumerate(series):
            ax.bar([i + (k - 1.5) * width for i in x], values, width, label=label, color=color)
        ax.axhline(20.0, color="black", lw=0.8, ls=":", label="20 ms extraction goal")
        for i, r in enumerate(sel):
            ax.annotate(f"{r['triangles'] / 1000:.0f}k tri", (i, max(v[i] for _, v, _ in series)),
                        textcoords="offset points", xytext=(0, 4), ha="center", fontsize=8)
        ax.set_xticks(x)
        ax.set_xticklabels([f"{r['grid']}^3" for r in sel])
        ax.set_yscale("log")
        ax.set_title(f"{scene} ({sel[0]['fluid_particles']} fluid particles)")
        ax.set_xlabel("surface grid (voxels along the longest side)")
        ax.grid(True, which="both", axis="y", alpha=0.3)
    axes[0].set_ylabel(f"ms per surface (GPU timestamps, {device})")
    axes[-1].legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(sys.argv[1], dpi=110)


if __name__ == "__main__":
    main()
