"""What an outfit costs against its garments simulated alone, at the defaults, in one process.

    python benchmarks/outfit_cost.py [--frames 45] [--outfits pants-under-top,...] [--out docs/data/benchmark_outfit.json]

For each outfit of ``scripts/simulate_outfits.py`` the outfit and each of its garments alone step the
same walk (0.5 s settle, then the motion), frame by frame in turn, each timed by CPU
(``time.process_time`` of its ``step_frame``, and for the outfit of finding its layers' offsets
off the body, as ``sim.run`` does every frame): the ratio of the outfit's CPU time to the sum of its
garments' is what dressing the body in them together costs over dressing it in each apart (the
garment-garment contacts, and self-contact's search over more triangles).
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _outfits() -> dict[str, list[str]]:
    spec = importlib.util.spec_from_file_location("simulate_outfits", ROOT / "scripts" / "simulate_outfits.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.OUTFITS


def measure(garments: list[str], frames: int) -> dict:
    import darts
    from sim.body_track import build_body_track
    from sim.engine.model import cloth_model
    from sim.engine.settings import SimSettings
    from sim.engine.simulation import Simulation
    from sim.outfit import layer_order, outfit_model

    body, settings = darts.load_body(), SimSettings()
    track = build_body_track(body, darts.load_motion("walk"), settings.fps, 0.5)
    dresses = [darts.load_garment(name) for name in garments]
    outfit = outfit_model(dresses, garments, body.shaped()[0][0].double().numpy(), body.faces)
    models = {"outfit": outfit.model, **{name: cloth_model(dart) for name, dart in zip(garments, dresses)}}
    sims = {name: Simulation(m, track.place_rest(m.rest), track.faces, track.vertices[0], settings, track.parts)
            for name, m in models.items()}
    cpu = dict.fromkeys(sims, 0.0)
    for k in range(1, min(frames + 1, len(track.vertices))):
        for name, simulation in sims.items():
            start = time.process_time()
            simulation.step_frame(track.vertices[k])
            if k > 1:  # the first frame compiles the kernels
                cpu[name] += time.process_time() - start
    alone = sum(cpu[name] for name in garments)
    inside, _ = layer_order(outfit, sims["outfit"].positions(), track.vertices[k], track.faces)
    return {"garments": garments, "frames": k - 1, "particles": {n: len(m.rest) for n, m in models.items()},
            "cpu_s": cpu, "ratio_outfit_to_sum_alone": cpu["outfit"] / alone, "layer_inside_last_frame": inside,
            "stable": all(s.measure().finite for s in sims.values())}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=45, help="frames stepped, the settle's 15 included")
    parser.add_argument("--outfits", help="comma-separated names (default: every outfit)")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "data" / "benchmark_outfit.json")
    args = parser.parse_args()
    outfits = _outfits()
    names = args.outfits.split(",") if args.outfits else list(outfits)
    rows = {}
    for name in names:
        row = rows[name] = measure(outfits[name], args.frames)
        alone = sum(v for k, v in row['cpu_s'].items() if k != 'outfit')
        print(f"{name}: outfit {row['cpu_s']['outfit']:.1f} s CPU, alone {alone:.1f} s "
              f"-> {row['ratio_outfit_to_sum_alone']:.2f}x; inside {row['layer_inside_last_frame']}", flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
