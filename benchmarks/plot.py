"""Plot the benchmark results (docs/data/benchmark_*.json) into docs/images/benchmarks.png: speed
against penetration for ours and Newton (``benchmark_newton_substeps.json``), our cost against
garment size and where the time goes (``benchmark_scaling.json``).

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

    comparison = json.loads((DATA / "benchmark_newton_substeps.json").read_text())["runs"]
    scaling = json.loads((DATA / "benchmark_scaling.json").read_text())["sizes"]
    figure, (bars, curve, shares) = plt.subplots(1, 3, figsize=(16, 4.6))

    # speed against quality: every run of the comparison (docs/benchmarks.md, "Against Newton")
    points = {}
    for run in comparison.values():
        substeps = run["scene"]["newton_substeps"]
        for name, result in run["results"].items():
            if result["stable"]:
                label = "ours (defaults)" if name == "ours" else f"Newton VBD {substeps} x 10"
                points[label] = (result["sim_fps"], 100 * result["max_penetration"])
    for label, (fps, penetration) in points.items():
        bars.scatter(fps, penetration, color="tab:blue" if label.startswith("ours") else "tab:gray", s=40)
        bars.annotate(label, (fps, penetration), textcoords="offset points", xytext=(6, 4), fontsize=8)
    bars.set_xscale("log")
    bars.set_yscale("log")
    bars.axhline(1.0, color="tab:red", linestyle=":", linewidth=1)
    bars.set_xlabel("simulated frames / s (CPU, log)")
    bars.set_ylabel("max penetration, % of particles (log)")
    scene = next(iter(comparison.values()))["scene"]
    bars.set_title(f"{scene['garment']} on {scene['motion']}, {scene['particles']} particles, {scene['frames']} frames",
                   fontsize=9)

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
