"""The docs' generated tables: each is written from its source (a JSON in ``docs/data/``, or a
declaration in the code) between markers in a Markdown file,

    <!-- table: NAME (python scripts/docs_tables.py) -->
    | ... |
    <!-- /table -->

so that a table cannot drift from the numbers it quotes: ``tests/test_docs_tables.py`` fails when
one differs from what its source gives.

    python scripts/docs_tables.py            # rewrite every table in place
    python scripts/docs_tables.py --check    # exit 1 naming the tables that differ
"""
from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "docs" / "data"


def _script(name: str, folder: str = "scripts"):
    """The module of ``FOLDER/NAME.py`` (its table renderer is the one its run prints)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(f"_docs_tables_{name}", ROOT / folder / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _block(text: str, index: int) -> list[str]:
    """The ``index``-th of the Markdown tables in ``text`` (tables apart by a blank line)."""
    return text.split("\n\n")[index].splitlines()


def _cell(value) -> str:
    return str(value).replace("|", "\\|")


def sim_settings() -> list[str]:
    """Every darts-sim setting from its one declaration (``sim.engine.settings.user_settings``)."""
    from sim.engine.settings import user_settings

    rows = ["| setting (`SimSettings`) | darts-sim flag | batch `[sim]` key | default | what the flag does |",
            "|---|---|---|---|---|"]
    for setting in user_settings():
        rows.append(f"| `{setting.name}` | `{setting.flag}` | `{setting.key}` | {_cell(setting.default_text)} | "
                    f"{_cell(setting.help)} |")
    return rows


def photo_outfits() -> list[str]:
    """The development photographs read as outfits (``docs/data/photo_outfits.json``, written by
    ``python scripts/photo_outfits.py``)."""
    rows = ["| photograph | truth | read (probability) | sleeve end | hem end | between legs | right |",
            "|---|---|---|---|---|---|---|"]
    for row in json.loads((DATA / "photo_outfits.json").read_text())["rows"]:
        read = ", ".join(f"{g['category']} ({100 * g['probability']:.0f} %)" for g in reversed(row["read"]))
        attributes = {}
        for garment in row["read"]:
            attributes.update({k: v for k, v in garment["attributes"].items() if isinstance(v, (int, float))})
        cells = ["–" if attributes.get(k) is None else f"{attributes[k]:.2f}"
                 for k in ("sleeve_end", "hem_end", "between_legs_fill")]
        truth = ", ".join(row["truth"]) + (" (ambiguous)" if row["ambiguous"] else "")
        rows.append(f"| {row['file']} | {truth} | {read} | {' | '.join(cells)} | {'yes' if row['right'] else 'no'} |")
    return rows


def imports() -> list[str]:
    """Meshes imported as DARTs (``docs/data/import.json``, written by ``python scripts/evaluate_import.py``)."""
    rows = ["| mesh | category (guessed) | scale | DART→mesh mean / p95 | mesh→DART mean / p95 | lines max | inside body "
            "| walk: stable, penetration, strain p99 | squat: the same |", "|---|---|---|---|---|---|---|---|---|"]

    def motion(r: dict) -> str:
        return (f"{'yes' if r['stable'] else 'no'} ({r['simulated_frames']} frames), {100 * r['max_penetration']:.2f} %, "
                f"{100 * r['strain_p99']:.0f} %")

    for name, r in json.loads((DATA / "import.json").read_text()).items():
        if "moved_out_of_body" in r:  # --own-mesh: the DART is the file (its openings the lines), moved out of the body
            moved = r["moved_out_of_body"]
            fit = f"the file, moved out of the body {moved['mean_mm']:.2f} / {moved['p95_mm']:.2f} | – | – | – "
        else:
            fit = (f"{r['dart_to_mesh']['mean_mm']:.2f} / {r['dart_to_mesh']['p95_mm']:.2f} | "
                   f"{r['mesh_to_dart']['mean_mm']:.2f} / {r['mesh_to_dart']['p95_mm']:.2f} | "
                   f"{r['feature_line_max_mm']:.1f} mm | {100 * r['inside_body']:.2f} % ")
        rows.append(f"| {name} | {r['category']}{' (guessed)' if 'category_guess_mm' in r else ''} | {r['scale']:.3f} | "
                    f"{fit}| {motion(r['walk'])} | {motion(r['squat'])} |")
    return rows


def import_round_trip(data: str) -> Callable[[], list[str]]:
    """Edited, remeshed DARTs imported back (``docs/data/<data>.json``, written by
    ``python scripts/import_round_trip.py``: seed 0, or ``--seed 1 --count 10 --collars 0``)."""
    def rows() -> list[str]:
        script, measured = _script("import_round_trip"), json.loads((DATA / f"{data}.json").read_text())
        return [*script.table(measured), "", script.summary(measured)]
    return rows


def simulation_results() -> list[str]:
    """Every shipped garment x motion at the defaults (``docs/data/simulation_table.json``, written
    by ``python scripts/simulate_table.py``)."""
    rows = json.loads((DATA / "simulation_table.json").read_text())
    return _block(_script("simulate_table").markdown(rows), 0)


def seam_regimes() -> list[str]:
    """Each garment's walk in each seam regime (the same JSON and script)."""
    rows = json.loads((DATA / "simulation_table.json").read_text())
    return _block(_script("simulate_table").markdown(rows), 1)


def outfits() -> list[str]:
    """The shipped outfits (``docs/data/outfits.json``, written by ``python scripts/simulate_outfits.py``)."""
    return _script("simulate_outfits").table(json.loads((DATA / "outfits.json").read_text())).splitlines()


def strain_waist() -> list[str]:
    """The long pants' strain against the waistband's hold (``docs/data/strain_waist_sweep.json``,
    written by ``python scripts/strain_waist_sweep.py``)."""
    return _script("strain_waist_sweep").table(json.loads((DATA / "strain_waist_sweep.json").read_text())).splitlines()


def crdl_comparison() -> list[str]:
    """The CRDL against handle-based Laplacian deformation and libigl's ARAP
    (``docs/data/crdl_comparison.json``, written by ``python scripts/compare_deformations.py``)."""
    rows = json.loads((DATA / "crdl_comparison.json").read_text())
    return _script("compare_deformations").markdown(rows).splitlines()


def photo_lengths() -> list[str]:
    """Where the photographs' garments end against the truth on the posed renders
    (``docs/data/photo_lengths_eval.json``, written by ``python scripts/evaluate_lengths.py``)."""
    return _script("evaluate_lengths").table(json.loads((DATA / "photo_lengths_eval.json").read_text()))


def _reconstruction_tables() -> list[list[str]]:
    """The tables ``python scripts/evaluate_reconstruction.py`` prints from ``docs/data/reconstruction.json``:
    the classifier's accuracy, line Chamfer on test and test_unseen, end to end."""
    text = _script("evaluate_reconstruction").tables(json.loads((DATA / "reconstruction.json").read_text()))
    return [block.splitlines() for block in text.split("\n\n") if block.startswith("|")]


def reconstruction(index: int) -> Callable[[], list[str]]:
    return lambda: _reconstruction_tables()[index]


def reconstruct_terms() -> list[str]:
    """The reconstruction's silhouette terms and picture sizes against CPU time
    (``docs/data/benchmark_reconstruct.json``, ``python benchmarks/reconstruct_speed.py``)."""
    rows = json.loads((DATA / "benchmark_reconstruct.json").read_text())
    return _script("reconstruct_speed", "benchmarks").table(rows).splitlines()


def photo_speed() -> list[str]:
    """A photograph to an outfit, end to end (``docs/data/benchmark_photo_speed.json``,
    ``python benchmarks/reconstruct_speed.py --photos ...``)."""
    rows = json.loads((DATA / "benchmark_photo_speed.json").read_text())["rows"]
    return _script("reconstruct_speed", "benchmarks").photo_table(rows).splitlines()


def materials() -> list[str]:
    """The materials a DART may carry (``darts.dart.model.MATERIALS``, their one declaration)."""
    from darts.dart.model import MATERIALS

    rows = ["| material | density (kg/m²) | stretch (N/m) | bend (N·m) | friction | thickness (m) |", "|---|---|---|---|---|---|"]
    for name, m in MATERIALS.items():
        bend = f"{m['bend_stiffness']:.0e}".replace("e-0", "e-")
        rows.append(f"| {name} | {m['density']:.2f} | {m['stretch_stiffness']:g} | {bend} | {m['friction']:g} | "
                    f"{m['thickness']:g} |")
    return rows


def shipped_garments() -> list[str]:
    """The shipped DARTs (``scenes/garments/``, made by ``python scripts/make_garments.py``)."""
    from darts.dart.io import load_dart
    from scenes import GARMENTS_DIR

    rows = ["| garment | category | vertices | faces | panels | seams | seam pairs | feature lines |",
            "|---|---|---|---|---|---|---|---|"]
    order = _script("make_garments").shipped_names()
    for name in order:
        dart = load_dart(GARMENTS_DIR / f"{name}.npz")
        rows.append(f"| {name} | {dart.category} | {len(dart.vertices)} | {len(dart.faces)} | {len(dart.panel_names)} | "
                    f"{len(dart.seams)} | {len(dart.pairs)} | {', '.join(dart.lines)} |")
    return rows


def dataset_parts() -> list[str]:
    """The dataset's parts (``docs/data/dataset_summary.json``, written by ``darts dataset make``)."""
    parts = json.loads((DATA / "dataset_summary.json").read_text())["samples_per_split"]
    names = {"test_unseen": "test_unseen (the test garments, unseen appearance)"}
    return ["| part | samples |", "|---|---|"] + [f"| {names.get(p, p)} | {parts[p]} |"
                                                 for p in ("train", "val", "test", "test_unseen")]


def batch_speed() -> list[str]:
    """A batch serially and on Ray (``docs/data/benchmark_batch.json``, ``python benchmarks/batch.py``)."""
    b = json.loads((DATA / "benchmark_batch.json").read_text())
    return ["| | wall time | jobs per hour | mean job |", "|---|---|---|---|",
            f"| serial loop | {b['serial_seconds']:.0f} s | {b['serial_jobs_per_hour']:.1f} | "
            f"{b['mean_job_seconds']['serial']:.1f} s |",
            f"| Ray, {b['workers']} workers | {b['ray_seconds']:.0f} s | {b['ray_jobs_per_hour']:.1f} | "
            f"{b['mean_job_seconds']['ray']:.1f} s |",
            f"| **ratio** | | **{b['speedup']:.3f}×** | |"]


def _median(rows: list[dict], key: str) -> float:
    import numpy as np

    return float(np.median([r[key] for r in rows if r.get(key) is not None]))


def posed_renders(name: str) -> Callable[[], list[str]]:
    """The held-out posed renders read with no mask and no camera (``docs/data/NAME.json``, written
    by ``python scripts/evaluate_photos.py --data ~/.cache/darts/posed-s101``): the person, the
    body fit, and the garment's category and mask by the parsing (issue 44) where it was run and by
    the garment network."""

    def rows() -> list[str]:
        data = json.loads((DATA / f"{name}.json").read_text())
        summary, pictures = data["summary"], data["pictures"]
        found = summary["found_per_category"].values()
        low, high = (min(int(f.split("/")[0]) for f in found), max(int(f.split("/")[0]) for f in found))
        count = summary["pictures"]
        table = [f"| {count} pictures, 256 × 256 | |", "|---|---|",
                 f"| person found | {summary['found']} ({100 * summary['found'] / count:.1f} %; every category "
                 f"{low}–{high} of {count // len(found)}) |",
                 "| person mask IoU against the truth (body and both garments), median | "
                 f"{summary['person_mask_iou_median']:.3f} |",
                 f"| body joints: the fitted body's 22 against the truth (joints in view), median | "
                 f"{summary['joint_error_px_median']:.1f} pixels, {summary['joint_error_pct_height_median']:.1f} % of the "
                 "person's height |"]
        if "parsing" in summary:
            table.append(f"| category: the parsing (every garment read, the one of the picture's kind) | "
                         f"**{100 * summary['parsing']['category_accuracy']:.1f} %** |")
            if "category_accuracy_every_garment" in summary["parsing"]:
                table.append(f"| category: the parsing, every garment worn (the other one too) | "
                             f"{100 * summary['parsing']['category_accuracy_every_garment']:.1f} % |")
        table += [f"| category: the garment network | {100 * summary['garment_network']['category_accuracy']:.1f} % |",
                  f"| category: the shipped classifier on the whole picture / on the garment alone (true mask) | "
                  f"{100 * summary['category_accuracy']:.1f} % / {100 * summary['category_accuracy_garment_alone']:.1f} % |"]
        if "parsing" in summary:
            table.append(f"| garment mask: the parsing's against the truth, IoU median | "
                         f"**{summary['parsing']['mask_iou_median']:.3f}** |")
        table.append(f"| garment mask: the garment network's against the truth, IoU median | "
                     f"{summary['garment_network']['mask_iou_median']:.3f} |")
        seconds = summary["seconds_median"]
        stages = [("person", seconds["person_s"]), ("body fit", seconds["body_fit_s"])]
        stages += [("parsing", _median(pictures, "parsing_s"))] if "parsing" in summary else []
        stages += [("garment network", seconds["garment_s"])]
        table.append(f"| CPU per picture, median: {' / '.join(n for n, _ in stages)} | "
                     f"{' / '.join(f'{v:.3f}' if v < 0.1 else f'{v:.2f}' for _, v in stages)} s |")
        return table

    return rows


def posed_reconstructions(name: str, photo_label: str) -> Callable[[], list[str]]:
    """``darts reconstruct`` on every third posed render (``docs/data/NAME.json``, ``python
    scripts/evaluate_photos.py --data ~/.cache/darts/posed-s101 --reconstruct --every 3``): with the
    true mask and category, and from the picture alone (``photo_label``), against the template."""

    def rows() -> list[str]:
        summary = json.loads((DATA / f"{name}.json").read_text())["summary"]
        table = [f"| {summary['pictures']} held-out pictures ({summary['found']} with a person), medians | reconstructed | "
                 "garment IoU | template's | surface Chamfer | template's | line Chamfer | template's |",
                 "|---|---|---|---|---|---|---|---|"]
        for kind, label in (("oracle", "the true mask and category given"), ("photo", photo_label)):
            r = summary[kind]
            done = (f"{r['reconstructed']}" if kind == "oracle" else
                    f"{r['reconstructed']} ({r['refused']} refused under 50 %; {r['category_right']} right)")
            table.append(f"| {label} | {done} | **{r['garment_iou_median']:.3f}** | {r['template_iou_median']:.3f} | "
                         f"{r['surface_chamfer_cm_median_category_right']:.2f} cm | "
                         f"{r['template_chamfer_cm_median_category_right']:.2f} cm | "
                         f"**{r['line_chamfer_cm_median_category_right']:.2f} cm** | "
                         f"{r['template_line_chamfer_cm_median_category_right']:.2f} cm |")
        return table

    return rows


def memory() -> list[str]:
    """Peak memory of a run against its length (``docs/data/benchmark_memory.json``, ``python benchmarks/memory.py``)."""
    m = json.loads((DATA / "benchmark_memory.json").read_text())
    return ["| frames | peak resident memory |", "|---|---|", f"| 120 (30 fps) | {m['peak_mib_120_frames']:.0f} MiB |",
            f"| 600 (150 fps) | {m['peak_mib_600_frames']:.0f} MiB |"]


def outfit_cost() -> list[str]:
    """An outfit against its garments alone (``docs/data/benchmark_outfit.json``, ``python benchmarks/outfit_cost.py``)."""
    rows = ["| outfit (inner first) | outfit CPU | garments alone, summed | ratio |", "|---|---|---|---|"]
    for r in json.loads((DATA / "benchmark_outfit.json").read_text()).values():
        alone = sum(r["cpu_s"][g] for g in r["garments"])
        rows.append(f"| {' + '.join(r['garments'])} | {r['cpu_s']['outfit']:.1f} s | {alone:.1f} s | "
                    f"{r['ratio_outfit_to_sum_alone']:.2f}× |")
    return rows


def startup() -> list[str]:
    """Start-up of the commands (``docs/data/benchmark_startup.json``, ``python benchmarks/startup.py``)."""
    rows = ["| command | before (CPU, peak memory) | now | faster | costliest imports now (ms) |", "|---|---|---|---|---|"]
    for command, r in json.loads((DATA / "benchmark_startup.json").read_text())["commands"].items():
        imports = ", ".join(f"{name} {us / 1000:.0f}" for name, us in r["costliest_imports_us"][:3])
        rows.append(f"| `{command}` | {r['baseline']['cpu_s']:.2f} s, {r['baseline']['peak_mib']:.0f} MiB | "
                    f"{r['now']['cpu_s']:.2f} s, {r['now']['peak_mib']:.0f} MiB | {r['speedup']:.1f}× | {imports} |")
    return rows


def scaling() -> list[str]:
    """Cost against garment size (``docs/data/benchmark_scaling.json``, ``python benchmarks/scaling.py``);
    the 6k top is the reference scene."""
    rows = ["| garment size | particles | simulated frames / s | µs per particle per substep |", "|---|---|---|---|"]
    for size, r in json.loads((DATA / "benchmark_scaling.json").read_text())["sizes"].items():
        fps = f"{r['sim_fps']:.3g}" if r["sim_fps"] >= 1 else f"{r['sim_fps']:.2f}"
        cells = [size, f"{r['particles']:,}", fps, f"{r['us_per_particle_substep']:.2f}"]
        if size == "6k":
            cells = ["**6k (reference)**", *(f"**{c}**" for c in cells[1:])]
        rows.append("| " + " | ".join(cells) + " |")
    return rows


def solver_defaults() -> list[str]:
    """Today's default against issue 30's on five scenes, configurations alternated in one process
    (``docs/data/benchmark_solver.json``, ``python benchmarks/solver_speed.py``)."""
    scenes = {"short-sleeve-top": "top", "short-skirt": "short skirt", "long-pants": "long pants"}
    rows = ["| scene | baseline frames / s (CPU) | default frames / s | ratio | strain mean / p99 / max | "
            "penetration sign / winding | worst stiff-seam gap | self-crossing edges |", "|---|---|---|---|---|---|---|---|"]

    def strain(r):
        return f"{100 * r['strain_mean']:.2f} / {100 * r['strain_p99']:.3g} / {100 * r['strain_max']:.0f}"

    def penetration(r):
        winding = 100 * r["max_penetration_winding"]
        return f"{100 * r['max_penetration']:.2f} / " + (f"{winding:.2f}" if winding < 10 else f"{winding:.1f}")

    for scene in json.loads((DATA / "benchmark_solver.json").read_text())["scenes"]:
        results = scene["results"]
        base = next(r for r in results.values() if r["ratio"] == 1.0)
        new = next(r for name, r in results.items() if name.startswith("default:"))
        rows.append(f"| {scenes[scene['garment']]}, {scene['motion']} | {base['sim_fps']:.2f} | {new['sim_fps']:.2f} | "
                    f"**{new['ratio']:.2f}×** | {strain(base)} → {strain(new)} % | {penetration(base)} → {penetration(new)} % | "
                    f"{1e3 * base['max_stiff_seam_gap']:.1f} → {1e3 * new['max_stiff_seam_gap']:.1f} mm | "
                    f"{base['max_self_crossing_edges']:,} → {new['max_self_crossing_edges']:,} |")
    return rows


def small_steps() -> list[str]:
    """The baseline, the default and the small-step lead on five scenes, each run several times
    (``docs/data/benchmark_small_steps.json``, ``python benchmarks/solver_speed.py --repeats``): each
    quality measure as its least–most over the runs."""
    rows = ["| scene | configuration | frames / s (CPU) | ratio | strain mean / p99 / max (%) | penetration sign / winding (%) "
            "| worst stiff-seam gap (mm) | self-crossing edges |", "|---|---|---|---|---|---|---|---|"]

    def spread(r, key, scale, form):
        low, high = (format(scale * v, form) for v in r["spread"][key])
        return low if low == high else f"{low}–{high}"

    for scene in json.loads((DATA / "benchmark_small_steps.json").read_text())["scenes"]:
        for name, r in scene["results"].items():
            label = "baseline" if r["ratio"] == 1.0 else "default" if name.startswith("default:") else "small steps"
            ratio = "1" if label == "baseline" else f"**{r['ratio']:.2f}×**"
            strain = " / ".join(spread(r, k, 100, f) for k, f in (("strain_mean", ".2f"), ("strain_p99", ".1f"),
                                                                   ("strain_max", ".0f")))
            penetration = " / ".join(spread(r, k, 100, ".2f") for k in ("max_penetration", "max_penetration_winding"))
            rows.append(f"| {scene['garment'].replace('-', ' ')}, {scene['motion']} | {label} | {r['sim_fps']:.2f} | {ratio} | "
                        f"{strain} | {penetration} | {spread(r, 'max_stiff_seam_gap', 1e3, '.1f')} | "
                        f"{spread(r, 'max_self_crossing_edges', 1, 'd')} |")
    return rows


def against_newton() -> list[str]:
    """Ours against NVIDIA Newton's solvers on one scene (``docs/data/benchmark_newton_substeps.json``,
    ``python benchmarks/compare_newton.py ... --newton-substeps N``; the once-a-frame VBD and the
    XPBD rows from the previous revision's ``benchmark_newton.json``)."""
    runs = json.loads((DATA / "benchmark_newton_substeps.json").read_text())["runs"]
    previous = json.loads((DATA / "benchmark_newton.json").read_text())["results"]
    ours = next(r["results"]["ours"] for r in runs.values() if "ours" in r["results"])

    def quality(r):
        penetration = 100 * r["max_penetration"]
        return (f"{100 * r['strain_mean']:.2f} / {100 * r['strain_p99']:.1f} % | "
                f"{penetration:.2f} %" if penetration < 1 else f"{100 * r['strain_mean']:.2f} / {100 * r['strain_p99']:.1f} % | "
                f"{penetration:.1f} %")

    rows = ["| solver | simulated frames / s (CPU) | ours / it | strain mean / p99 | max penetration | stable |",
            "|---|---|---|---|---|---|",
            f"| ours (defaults: XPBD 20 × 2, tethers, self-contact) | {ours['sim_fps']:.2f} | 1 | {quality(ours)} | yes |"]
    vbd = previous["newton-vbd-no-self-contact"]
    rows.append("| Newton VBD 10 × 10, no self-contact, contacts once a frame (its documented loop; the previous revision, "
                f"wall time) | {vbd['sim_fps']:.3f} | - | {quality(vbd)} | yes |")
    for run in sorted(runs.values(), key=lambda r: r["scene"]["newton_substeps"]):
        n, r = run["scene"]["newton_substeps"], run["results"]["newton-vbd-no-self-contact"]
        what = "no self-contact, contacts every substep" if n == 10 else "the same"
        rows.append(f"| Newton VBD {n} × 10, {what} | {r['sim_fps']:.3f} | {ours['sim_fps'] / r['sim_fps']:.0f} | "
                    f"{quality(r)} | yes |")
    xpbd = previous["newton-xpbd"]
    rows.append(f"| Newton XPBD 10 × 10 | - | - | - | - | no ({xpbd['message']}) |")
    return rows


#: the profile's rows (benchmarks/solver_speed.py's PROFILE_ROWS) as the docs name them
_PROFILE_LABELS = {
    "body contact search and tracking": "body contact search and tracking (body placed and refit every substep)",
    "constraint sweeps, contact projection, friction, velocities (one captured block)":
        "constraint sweeps, contact projection, friction, velocities (one captured block a substep)",
    "whole frame": "whole frame (with the profiler's overhead)",
}


def default_profile() -> list[str]:
    """Where the default's time goes on the top's walk: cProfile of a copy run alongside
    (``profile_ms_per_frame`` of ``docs/data/benchmark_solver.json``)."""
    scene = json.loads((DATA / "benchmark_solver.json").read_text())["scenes"][0]
    profile = next(r for name, r in scene["results"].items() if name.startswith("default:"))["profile_ms_per_frame"]
    whole = profile["whole frame"]
    return ["| part | ms / frame | share |", "|---|---|---|"] + [
        f"| {_PROFILE_LABELS.get(label, label)} | {ms:.1f} | {100 * ms / whole:.0f} % |" for label, ms in profile.items()]


def kernel_profile() -> list[str]:
    """The default's frame on the top's walk, kernel by kernel, launch by launch (``docs/data/kernel_profile.json``,
    ``python benchmarks/kernel_profile.py``)."""
    profile = json.loads((DATA / "kernel_profile.json").read_text())
    whole = profile["frame_ms_launch_by_launch"]
    rows = ["| kernel (or BVH refit) | calls / frame | ms / frame | share |", "|---|---|---|---|"]
    for name, k in sorted(profile["kernels"].items(), key=lambda item: -item[1]["ms_per_frame"]):
        rows.append(f"| {name} | {k['calls_per_frame']:g} | {k['ms_per_frame']:.1f} | {100 * k['ms_per_frame'] / whole:.0f} % |")
    rows.append(f"| whole frame, launch by launch | | {whole:.1f} | 100 % |")
    return rows


def posed_lines() -> list[str]:
    """The posed line regressor on the held-out posed renders, lines back in the rest pose, mean per
    group of categories (``docs/data/posed_lines_eval.json``, ``python scripts/evaluate_posed_lines.py``)."""
    import numpy as np

    from darts.templates.categories import CATEGORIES

    groups = {"Upper": ("top",), "Lower": ("pants",), "Skirts": ("skirt", "dress")}
    pictures = json.loads((DATA / "posed_lines_eval.json").read_text())["rows"]

    def means(key: str) -> str:
        per_group = [np.mean([r[key] for r in pictures if CATEGORIES[r["category"]].family in families])
                     for families in groups.values()]
        return " | ".join(f"{v:.2f}" for v in [*per_group, np.mean([r[key] for r in pictures])])

    return ["| method | Upper | Lower | Skirts | all |", "|---|---|---|---|---|",
            f"| template on the body (no network) | {means('rest_template_cm')} |",
            f"| Ours, posed | {means('rest_cm')} |"]


def shipped_motions() -> list[str]:
    """The shipped motions (``scenes/motions/``, made by ``python scripts/make_motions.py``), posed on
    the bundled body: the lowest vertex per frame, its least and most over the motion; the largest
    joint rotation below the root (degrees)."""
    import numpy as np

    from darts.body.io import load_body
    from darts.motion.amass import load_motion
    from darts.motion.posing import pose_sequence
    from darts.shipped import shipped_motions
    from scenes import MOTIONS_DIR

    body = load_body()
    rows = ["| motion | frames | fps | duration (s) | travel (m) | lowest point z (m), min / max | largest joint angle (deg) |",
            "|---|---|---|---|---|---|---|"]
    order = ["walk", "run", "wave", "jumping_jacks", "twist", "squat"]
    for name in order + sorted(set(shipped_motions()) - set(order)):
        motion = load_motion(MOTIONS_DIR / f"{name}.npz")
        vertices, _ = pose_sequence(body, motion)
        lowest = vertices[..., 2].min(axis=1)
        angle = np.degrees(np.linalg.norm(motion.parts()["body_pose"][:, 1:], axis=2)).max()
        travel = float(np.linalg.norm(motion.trans[-1, :2] - motion.trans[0, :2]))
        # rounded first, then + 0.0: a value within rounding of zero prints +0.000 whatever its sign
        # (the last bits of the posed body's lowest point differ between CPUs)
        low, high = (f"{round(float(v), 3) + 0.0:+.3f}".replace("-", "−") for v in (lowest.min(), lowest.max()))
        rows.append(f"| {name} | {motion.num_frames} | {motion.fps:g} | {motion.duration:.1f} | {travel:.2f} | {low} / {high} | "
                    f"{angle:.0f} |")
    return rows


def shipped_weights() -> list[str]:
    """The shipped networks (``darts/regress/weights/*.pt``): each checkpoint's own record (its
    command, dataset, last epoch's validation numbers) and file size; the posed regressor's held-out
    number from ``docs/data/posed_lines_eval.json``."""
    import re

    import torch

    folder = ROOT / "darts" / "regress" / "weights"
    rows = ["| file | made by | size | numbers |", "|---|---|---|---|"]
    for name in ("classifier", "lines_ours", "lines_im-stm", "lines_p2m-gcn", "lines_posed"):
        path = folder / f"{name}.pt"
        record = torch.load(path, map_location="cpu", weights_only=False)["record"]
        data = re.search(r"--data (\S+)", record["command"]).group(1).replace("/root/.cache", "~/.cache")
        command = re.sub(r" --out \S+", "", record["command"]).replace("/root/.cache", "~/.cache")
        command += "" if "--seed" in command else f" --seed {record['seed']}"
        if "--posed" in command:
            recipe = record["dataset"]["command"] if isinstance(record["dataset"], dict) else ""
            command = f"`{command}` (on `{recipe.replace('OUT_DIR', data)}`)" if recipe else f"`{command}`"
        else:
            command = f"`{command}`"
        if "val_accuracy" in record:
            numbers = (f"val {100 * record['val_accuracy'][-1]:.1f} % "
                       f"({100 * record['val_accuracy_garment_alone'][-1]:.1f} % garment alone)")
        else:
            numbers = f"val {record['val_chamfer_cm'][-1]:.2f} cm"
        if name == "lines_posed":
            held_out = json.loads((DATA / "posed_lines_eval.json").read_text())["summary"]["rest_cm_mean"]
            numbers += f" (posed frame); held-out {held_out:.2f} cm (rest)"
        rows.append(f"| `{path.name}` | {command} | {path.stat().st_size / 1e6:.1f} MB | {numbers} |")
    return rows


#: table name -> (the Markdown file it lives in, the function that writes its rows)
def fuzz() -> list[str]:
    """The fuzz run (``docs/data/fuzz.json``, written by ``python scripts/fuzz_report.py``)."""
    return _script("fuzz_report").table(json.loads((DATA / "fuzz.json").read_text()))


TABLES: dict[str, tuple[str, Callable[[], list[str]]]] = {
    "fuzz": ("docs/api.md", fuzz),
    "sim-settings": ("docs/simulation.md", sim_settings),
    "photo-outfits": ("docs/reconstruction.md", photo_outfits),
    "import": ("docs/import.md", imports),
    "import-round-trip": ("docs/import.md", import_round_trip("import_round_trip")),
    "import-round-trip-held-out": ("docs/import.md", import_round_trip("import_round_trip_s1")),
    "simulation-results": ("docs/simulation.md", simulation_results),
    "seam-regimes": ("docs/simulation.md", seam_regimes),
    "outfits": ("docs/simulation.md", outfits),
    "strain-waist": ("docs/simulation.md", strain_waist),
    "crdl-comparison": ("docs/crdl.md", crdl_comparison),
    "classifier": ("docs/reconstruction.md", reconstruction(0)),
    "lines-test": ("docs/reconstruction.md", reconstruction(1)),
    "lines-test-unseen": ("docs/reconstruction.md", reconstruction(2)),
    "end-to-end": ("docs/reconstruction.md", reconstruction(3)),
    "posed-lines": ("docs/reconstruction.md", posed_lines),
    "photo-lengths": ("docs/reconstruction.md", photo_lengths),
    "shipped-weights": ("docs/reconstruction.md", shipped_weights),
    "reconstruct-terms": ("docs/benchmarks.md", reconstruct_terms),
    "solver-defaults": ("docs/benchmarks.md", solver_defaults),
    "default-profile": ("docs/benchmarks.md", default_profile),
    "kernel-profile": ("docs/benchmarks.md", kernel_profile),
    "small-steps": ("docs/benchmarks.md", small_steps),
    "against-newton": ("docs/benchmarks.md", against_newton),
    "memory": ("docs/benchmarks.md", memory),
    "scaling": ("docs/benchmarks.md", scaling),
    "outfit-cost": ("docs/benchmarks.md", outfit_cost),
    "startup": ("docs/benchmarks.md", startup),
    "photo-speed": ("docs/benchmarks.md", photo_speed),
    "materials": ("docs/simulation.md", materials),
    "shipped-garments": ("docs/templates.md", shipped_garments),
    "shipped-motions": ("docs/motions.md", shipped_motions),
    "dataset-parts": ("docs/dataset.md", dataset_parts),
    "posed-renders-before": ("docs/reconstruction.md", posed_renders("photo_posed_eval")),
    "posed-renders": ("docs/reconstruction.md", posed_renders("photo_posed_parsing")),
    "posed-reconstructions-before": ("docs/reconstruction.md",
                                     posed_reconstructions("photo_posed_reconstruct", "nothing given (garment network)")),
    "posed-reconstructions": ("docs/reconstruction.md",
                              posed_reconstructions("photo_posed_reconstruct_parsing", "nothing given (parsing)")),
    "batch-speed": ("docs/batch.md", batch_speed),
}


def _pattern(name: str) -> re.Pattern:
    return re.compile(rf"(<!-- table: {re.escape(name)} [^\n]*-->\n)(.*?)(<!-- /table -->)", re.S)


def rendered(name: str) -> tuple[Path, str, str]:
    """(the file, its text now, its text with table ``name`` written from its source)."""
    doc, rows = TABLES[name]
    path = ROOT / doc
    text = path.read_text()
    pattern = _pattern(name)
    if not pattern.search(text):
        raise SystemExit(f"{doc}: no '<!-- table: {name} ... -->' marker")
    return path, text, pattern.sub(lambda m: m.group(1) + "\n".join(rows()) + "\n" + m.group(3), text, count=1)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="only say which tables differ from their source")
    parser.add_argument("names", nargs="*", metavar="NAME", help=f"the tables (default: all of {', '.join(TABLES)})")
    args = parser.parse_args()
    unknown = sorted(set(args.names) - set(TABLES))
    if unknown:
        parser.error(f"unknown table {', '.join(unknown)} (known: {', '.join(TABLES)})")
    stale = []
    for name in args.names or TABLES:
        path, text, new = rendered(name)
        if new != text:
            stale.append(f"{path.relative_to(ROOT)}: table '{name}'")
            if not args.check:
                path.write_text(new)
    if args.check and stale:
        print("out of date (python scripts/docs_tables.py): " + "; ".join(stale), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    raise SystemExit(main())
