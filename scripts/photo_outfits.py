"""Every garment read from real photographs of people, against their labels: the development set in
``../shared/photos/`` (``labels.json``), or any folder laid out the same way.

    python scripts/photo_outfits.py [--photos ../shared/photos] [--json docs/data/photo_outfits.json]

Per photograph: the garments ``darts.read_outfit`` reads (given nothing but the picture), each with
its category, probability and the attributes measured (sleeve end, hem end as s along the limb:
0 shoulder or hip, 0.5 elbow or knee, 1 wrist or ankle; the fill between the legs; one piece or
two), against the labelled garments; a photograph counts as right when the categories read are
exactly the labelled ones. CPU seconds (``time.process_time``) per photograph, one core, after a
first photograph has loaded the models. Rewrites its table in docs/reconstruction.md
(``scripts/docs_tables.py``).
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photos", type=Path, default=Path(__file__).parents[1].parent / "shared" / "photos")
    parser.add_argument("--json", type=Path, default=Path("docs/data/photo_outfits.json"))
    args = parser.parse_args()
    import torch

    import darts

    torch.set_num_threads(1)
    labels = json.loads((args.photos / "labels.json").read_text())
    rows = []
    for entry in labels:
        started = time.process_time()
        outfit = darts.read_outfit(args.photos / entry["file"])
        seconds = time.process_time() - started
        read = sorted(g.category for g in outfit.garments)
        rows.append({"file": entry["file"], "truth": entry["garments"], "ambiguous": entry["ambiguous"],
                     "full_body": entry["full_body"], "read": [g.as_dict() for g in outfit.garments],
                     "notes": outfit.notes, "right": read == sorted(entry["garments"]), "cpu_s": round(seconds, 2)})
    clear = [r for r in rows if not r["ambiguous"]]
    summary = {"photographs": len(rows), "unambiguous": len(clear), "unambiguous_right": sum(r["right"] for r in clear),
               "garments_right": sum(g in [x["category"] for x in r["read"]] for r in clear for g in r["truth"]),
               "garments": sum(len(r["truth"]) for r in clear)}
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({"command": "python scripts/photo_outfits.py", "summary": summary, "rows": rows},
                                    indent=1) + "\n")
    from docs_tables import rendered  # scripts/docs_tables.py, beside this script

    path, _, text = rendered("photo-outfits")
    path.write_text(text)
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
