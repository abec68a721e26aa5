"""Plot the benchmark results (docs/data/benchmark_*.json) into docs/images/benchmarks.png.

    python benchmarks/plot.py
"""
from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "docs" / "data"
#: Kernels grouped by the part of the step they belong to.
GROUPS = {
    "body contact search": ("find_contacts",),
    "self-contact search (vertex-triangle)": ("find_self_contacts",),
    "edge-edge contacts (candidates, projection)": ("find_edge_contacts", "resolve_edge_contacts"),
    "contact tracking and projection": ("track_contacts", "resolve_contacts", "resolve_self_contacts", "apply_averaged",
                                        "apply_friction"),
    "stretch and seams": ("solve_distances",),
    "bending": ("solve_bending",),
    "BVH refits": ("bvh refit",),
}


def main() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    import numpy as np

    newton = json.loads((DATA / "benchmark_newton.json").read_text())
    scaling = json.loads((DATA / "benchmark_scaling.json").read_text())["sizes"]
    figure, (bars, curve, shares) = plt.subplots(1, 3, figsize=(16, 4.6))

    names = list(newton["results"])
    fps = [newton["results"][n]["sim_fps"] for n in names]
    colors = ["tab:blue" if n == "ours" else ("tab:gray" if newton["results"][n]["stable"] else "tab:red") for n in names]
    bars.bar(names, [max(f, 1e-4) for f in fps], color=colors)
    bars.set_yscale("log")
    bars.tick_params(axis="x", labelrotation=30, labelsize=8)
    bars.set_ylabel("simulated frames / s (log)")
    scene = newton["scene"]
    bars.set_title(f"{scene['garment']} on {scene['motion']}, {scene['particles']} particles, {scene['substeps']} substeps",
                   fontsize=9)
    for x, (name, f) in enumerate(zip(names, fps)):
        label = f"{f:.3g}" if newton["results"][name]["stable"] else "blew up"
        bars.text(x, max(f, 1e-4) * 1.15, label, ha="center", fontsize=8)

    sizes = list(scaling)
    particles = np.array([scaling[s]["particles"] for s in sizes])
    curve.plot(particles, [scaling[s]["us_per_particle_substep"] for s in sizes], "o-", color="tab:blue")
    curve.set_xscale("log")
    curve.set_xticks(particles, [f"{p / 1000:.1f}k" for p in particles], minor=False)
    curve.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    curve.set_xlabel("particles")
    curve.set_ylabel("µs per particle per substep", color="tab:blue")
    twin = curve.twinx()
    twin.plot(particles, [scaling[s]["sim_fps"] for s in sizes], "s--", color="tab:orange")
    twin.set_yscale("log")
    twin.set_ylabel("simulated frames / s", color="tab:orange")
    curve.set_title("our solver: 10 substeps x 4 iterations, self-contact on", fontsize=9)

    bottom = np.zeros(len(sizes))
    for group, kernels in GROUPS.items():
        share = np.array([sum(scaling[s]["share"].get(k, 0.0) for k in kernels) for s in sizes])
        shares.bar(sizes, share, bottom=bottom, label=group)
        bottom += share
    shares.bar(sizes, 1.0 - bottom, bottom=bottom, label="other kernels and Python", color="lightgray")
    shares.set_ylabel("share of the frame time")
    shares.set_title("where the time goes", fontsize=9)
    shares.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    figure.tight_layout()
    out = ROOT / "docs" / "images" / "benchmarks.png"
    figure.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
