"""`darts reconstruct`'s speed and quality by silhouette term and picture size, on held-out pictures;
or, with --photos, its end-to-end CPU time on photographs.

    python benchmarks/reconstruct_speed.py --data ~/.cache/darts/dataset-s7 [--split test] [--count 20]
        [--terms soft:1,outline:1] [--sizes 224,1024]
    python benchmarks/reconstruct_speed.py --photos PHOTO [PHOTO ...]   # docs/data/benchmark_photo_speed.json

With --photos, each photograph goes through ``darts reconstruct PHOTO -o OUT_DIR`` in a new process
(start-up included), timed by that process's CPU (user + system).

Each picture (image, garment mask, camera, body shape, ground-truth drape: ``darts dataset make``)
is reconstructed end to end (classifier, regressor, template, CRDL with the silhouette term) by
every term at every size, configurations alternated picture by picture in one process, one
thread; a size above the picture's is the picture upscaled (image bicubic, mask bilinear then
thresholded at half, camera intrinsics scaled), a 1024 x 1024 picture standing for a 1-megapixel
photograph. Timed by CPU (``time.process_time`` of the whole reconstruction, start-up excluded),
with the pipeline's own stage times. Quality against the picture's ground truth at its own size
(``darts.regress.quality``): surface Chamfer (cm, unsquared, both directions averaged) and the
mask IoU of the garment's render with the body in front. The soft term is only run at the
dataset's size unless ``--soft-everywhere`` (at 1024 px it takes minutes an iteration).
Writes docs/data/benchmark_reconstruct.json and prints the table of docs/benchmarks.md.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def upscaled(image: np.ndarray, mask: np.ndarray, camera, size: int):
    """The picture at ``size`` x ``size`` pixels (square pictures only), its mask and camera."""
    from PIL import Image

    big = np.asarray(Image.fromarray(image).resize((size, size), Image.BICUBIC))
    soft = np.asarray(Image.fromarray((mask * 255).astype(np.uint8)).resize((size, size), Image.BILINEAR))
    return big, soft > 127, camera.resized(size, size)


def photographs(paths: list[Path], out: Path) -> None:
    """``darts reconstruct PHOTO -o OUT_DIR`` end to end on each photograph, as a user runs it (a new
    process: start-up, imports and model loading included), timed by the child process's CPU
    (user + system, ``resource.getrusage(RUSAGE_CHILDREN)``); writes ``out`` and prints a table."""
    import resource
    import subprocess
    import sys
    import tempfile

    rows = []
    for path in paths:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        with tempfile.TemporaryDirectory() as folder:
            run = subprocess.run([sys.executable, "-m", "darts.cli.main", "reconstruct", str(path), "-o",
                                  str(Path(folder) / "outfit")], capture_output=True, text=True)
            report = json.loads((Path(folder) / "outfit" / "report.json").read_text()) if run.returncode == 0 else None
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        rows.append({"photo": path.name, "exit": run.returncode, "cpu_s": round(cpu, 2),
                     "garments": [g["category"] for g in report["garments"]] if report else None,
                     "vertices": [g["vertices"] for g in report["garments"]] if report else None})
        print(json.dumps(rows[-1]), flush=True)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"command": "python benchmarks/reconstruct_speed.py --photos ...", "rows": rows}, indent=1))
    print(photo_table(rows))


def photo_table(rows: list[dict]) -> str:
    """Per photograph: the garments reconstructed, their vertices, CPU seconds end to end."""
    lines = ["| photograph | garments | vertices | CPU s |", "|---|---|---|---|"]
    lines += [f"| {row['photo']} | {', '.join(row['garments'] or ['refused'])} | "
              f"{', '.join(map(str, row['vertices'] or []))} | {row['cpu_s']:.1f} |" for row in rows]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photos", type=Path, nargs="+", metavar="PHOTO",
                        help="instead: darts reconstruct PHOTO -o OUT_DIR end to end on each, CPU of the whole process")
    parser.add_argument("--data", type=Path)
    parser.add_argument("--split", default="test")
    parser.add_argument("--count", type=int, default=20)
    parser.add_argument("--terms", default="soft:1,outline:1", help="NAME:WEIGHT, comma-separated")
    parser.add_argument("--sizes", default="224,1024")
    parser.add_argument("--soft-everywhere", action="store_true")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "data" / "benchmark_reconstruct.json")
    args = parser.parse_args()
    if args.photos:
        return photographs(args.photos, ROOT / "docs" / "data" / "benchmark_photo_speed.json")
    if args.data is None:
        parser.error("--data or --photos is needed")

    import torch

    torch.set_num_threads(1)
    from darts.body.io import load_body
    from darts.camera import Camera
    from darts.fileio import read_image, read_npz
    from darts.regress.pipeline import reconstruct
    from darts.regress.quality import reconstruction_measures

    body = load_body(None)
    folders = sorted(p for p in (args.data / args.split).glob("*") if (p / "image.png").is_file())[:args.count]
    terms = [(name, float(weight)) for name, weight in (t.split(":") for t in args.terms.split(","))]
    sizes = [int(s) for s in args.sizes.split(",")]
    rows = []
    for folder in folders:
        meta = json.loads((folder / "meta.json").read_text())
        image, mask = read_image(folder / "image.png"), read_image(folder / "mask.png", "L") > 127
        camera = Camera.from_json(folder / "camera.json")
        draped = read_npz(folder / "draped.npz")
        for size in sizes:
            picture = (image, mask, camera) if size == image.shape[1] else upscaled(image, mask, camera, size)
            for name, weight in terms:
                if name == "soft" and size != image.shape[1] and not args.soft_everywhere:
                    continue
                start = time.process_time()
                result = reconstruct(picture[0], body, None, picture[2], picture[1], betas=meta["betas"],
                                     silhouette_term=name, silhouette_weight=weight)
                cpu = time.process_time() - start
                row = {"sample": folder.name, "category": meta["category"], "predicted": result.report["category"],
                       "size": size, "term": name, "weight": weight, "cpu_s": cpu, "times": result.report["times"],
                       "iterations": result.report["crdl"]["iterations"],
                       **reconstruction_measures(result.dart, draped, camera, mask, body, meta["betas"])}
                rows.append(row)
                print(f"{folder.name} {size} {name}:{weight:g}: {cpu:.1f} s CPU, crdl {row['times']['crdl_s']:.1f} s, "
                      f"chamfer {row['surface_chamfer_cm']:.2f} cm, IoU {row['mask_iou']:.3f}", flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(rows, indent=1))
    print(table(rows))


def table(rows: list[dict]) -> str:
    """Per (term, weight, size): pictures, right categories, CPU seconds (median, max), CRDL
    seconds (median), surface Chamfer (mean, cm) and mask IoU (mean)."""
    lines = ["| term | size (px) | pictures | CPU s, median / max | CRDL s, median | surface Chamfer (cm) | mask IoU |",
             "|---|---|---|---|---|---|---|"]
    keys = sorted({(r["term"], r["weight"], r["size"]) for r in rows}, key=lambda k: (k[2], k[0], k[1]))
    for term, weight, size in keys:
        mine = [r for r in rows if (r["term"], r["weight"], r["size"]) == (term, weight, size)]
        cpu = np.array([r["cpu_s"] for r in mine])
        lines.append(f"| {term} (weight {weight:g}) | {size} | {len(mine)} | {np.median(cpu):.1f} / {cpu.max():.1f} | "
                     f"{np.median([r['times']['crdl_s'] for r in mine]):.1f} | "
                     f"{np.mean([r['surface_chamfer_cm'] for r in mine]):.2f} | {np.mean([r['mask_iou'] for r in mine]):.3f} |")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
