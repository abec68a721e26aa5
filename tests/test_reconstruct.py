"""`darts reconstruct` and `darts classify` on the shipped sample picture (a held-out test picture of
the dataset), and their bad input."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch
from PIL import Image, ImageFilter

from darts.dart.io import load_dart
from darts.fileio import read_npz, save_npz
from darts.regress.data import initial_lines
from darts.templates.categories import CATEGORIES

SAMPLE = Path(__file__).parents[1] / "scenes" / "reconstruct"
META = json.loads((SAMPLE / "sample.json").read_text())
#: a half-length portrait in a uniform jacket, shipped with matplotlib: no garment of the ten categories
PORTRAIT = Path(__import__("matplotlib").get_data_path()) / "sample_data" / "grace_hopper.jpg"


def _line_error_cm(lines: dict, truth: dict) -> float:
    """Unsquared Chamfer (cm, both directions averaged) over the lines."""
    errors = []
    for name, points in truth.items():
        d = np.linalg.norm(np.asarray(lines[name])[:, None] - points[None], axis=2)
        errors.append(50 * (d.min(1).mean() + d.min(0).mean()))
    return float(np.mean(errors))


def test_classify_names_the_sample_garment(run_darts):
    code, out, err = run_darts("classify", SAMPLE / "image.png", "--json", "--mask", SAMPLE / "mask.png")
    assert code == 0, err
    ranked = json.loads(out)
    assert ranked[0]["category"] == META["category"] and ranked[0]["probability"] > 0.5
    assert len(ranked) == 3 and ranked[0]["probability"] >= ranked[1]["probability"]


@pytest.mark.parametrize("picture", ["gift box", "noise", "tiny", "blank"])
def test_classify_without_a_mask_refuses_a_picture_without_a_person(run_darts, tmp_path, picture):
    """A picture given alone is a photograph: the person check of ``reconstruct`` runs first, so a
    product photograph of a gift box, noise, a 1 x 1 or a blank picture get one line and exit 2
    instead of a category."""
    path = Path(__import__("matplotlib").get_data_path()) / "sample_data" / "Minduka_Present_Blue_Pack.png"
    if picture != "gift box":
        path = tmp_path / "picture.png"
        size = 1 if picture == "tiny" else 224
        pixels = (np.random.default_rng(0).integers(0, 256, (size, size, 3)) if picture == "noise"
                  else np.full((size, size, 3), 128))
        Image.fromarray(pixels.astype(np.uint8)).save(path)
    code, out, err = run_darts("classify", path)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    expected = {"tiny": "is 1x1 pixels: too small", "blank": "too blurred or blank"}.get(picture, "shows no person")
    assert f"{path.name}: " in err and expected in err, err


def test_classify_without_a_mask_reads_the_sample_render(run_darts):
    """The sample render (the faceless body in a short-sleeve top, its hands and feet out of the
    picture) holds a person for the detector only in its mirror image (score 0.91, presence 0.97):
    read there, the top comes out of the right category and the legs as out of the picture."""
    code, out, err = run_darts("classify", SAMPLE / "image.png", "--json")
    assert code == 0, err
    garments = json.loads(out)["garments"]
    assert [g["category"] for g in garments] == [META["category"]] and garments[0]["probability"] > 0.5


def test_the_garment_alone_hides_everything_outside_its_mask():
    """With a mask the classifier's input outside it is one grey whatever the background."""
    from darts.fileio import read_image
    from darts.regress.pipeline import network_input, network_mask
    from darts.regress.train import NEUTRAL, garment_only

    image, mask = read_image(SAMPLE / "image.png"), read_image(SAMPLE / "mask.png", "L") > 127
    other = image.copy()
    other[~mask] = 255 - other[~mask]
    x, y = (garment_only(network_input(i), network_mask(mask)) for i in (image, other))
    assert torch.equal(x, y) and torch.all(x[0][:, ~torch.from_numpy(mask)] == NEUTRAL)


@pytest.mark.slow
def test_reconstruct_then_simulate_the_sample(run_darts, tmp_path):
    still = tmp_path / "still.npz"  # a three-frame AMASS motion: the body standing in its rest pose
    save_npz(still, poses=np.zeros((3, 156)), trans=np.tile([0.0, 0.0, 1.0], (3, 1)), betas=np.zeros(16),
             gender=np.array("neutral"), mocap_framerate=np.array(30.0))
    out, report, usd = tmp_path / "garment.npz", tmp_path / "report.json", tmp_path / "sim.usdc"
    code, stdout, err = run_darts("reconstruct", SAMPLE / "image.png", "--mask", SAMPLE / "mask.png", "--camera",
                                  SAMPLE / "camera.json", "--betas", *META["betas"], "--edge-length", "0.04",
                                  "-o", out, "--report", report, "--simulate", still, "--sim-out", usd)
    assert code == 0, err
    data = json.loads(report.read_text())
    assert data["category"] == META["category"] and 0.5 < data["probability"] <= 1.0 and data["silhouette"]
    assert {"classify_s", "regress_s", "template_s", "crdl_s", "total_s"} <= set(data["times"])
    truth = read_npz(SAMPLE / "lines.npz")
    template = dict(zip(CATEGORIES[META["category"]].line_names, initial_lines(META["category"])))
    regressed = _line_error_cm(data["lines"], truth)
    assert regressed < 0.6 * _line_error_cm(template, truth), (regressed, _line_error_cm(template, truth))
    dart = load_dart(out)
    assert dart.category == META["category"] and len(dart.seams) > 0 and np.allclose(dart.body_betas, META["betas"], atol=1e-4)
    assert data["crdl"]["penetration"] <= 0.01 and data["crdl"]["handle_rmse"] < 0.01
    assert usd.is_file() and "wrote" in stdout


def _png_header(path, width: int, height: int) -> None:
    """A PNG whose header says ``width`` x ``height`` pixels, with no image data: what a decompression
    bomb shows before it is decoded."""
    import struct
    import zlib

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
                     + chunk(b"IDAT", zlib.compress(b"")) + chunk(b"IEND", b""))


@pytest.mark.parametrize("command, where", [("reconstruct", "image"), ("classify", "image"), ("classify", "mask"),
                                            ("reconstruct", "mask")])
@pytest.mark.parametrize("size", [20000, 10000])
def test_huge_images_are_refused_before_they_are_decoded(command, where, size, tmp_path, run_darts):
    """A 20000 x 20000 (400 megapixel) or 10000 x 10000 header, as the picture or as its mask: one
    line naming the file and its size, exit 2, nothing written (PIL alone raised its decompression
    bomb error, or decoded 100 megapixels into 3 GB)."""
    huge = tmp_path / "huge.png"
    _png_header(huge, size, size)
    image, mask = (huge, SAMPLE / "mask.png") if where == "image" else (SAMPLE / "image.png", huge)
    out = tmp_path / "garment.npz"
    extra = ["-o", out, "--camera", SAMPLE / "camera.json"] if command == "reconstruct" else []
    code, stdout, err = run_darts(command, image, "--mask", mask, *extra)
    assert code == 2 and stdout == "" and len(err.strip().splitlines()) == 1, err
    assert f"huge.png: the image is {size}x{size} pixels" in err and "at most 64 megapixels" in err, err
    assert list(tmp_path.iterdir()) == [huge]


@pytest.mark.parametrize("case, problem", [
    ("not an image", "not an image"),
    ("tiny", "is 1x1 pixels: too small"),
    ("blank", "too blurred or blank"),
    ("blurred", "too blurred or blank"),
    ("mask size", "the mask is 100x100 pixels but the image is 224x224"),
    ("camera", "not a JSON camera"),
    ("category", "unknown category 'poncho'"),
])
def test_bad_reconstruct_input_is_one_line_exit_2_and_no_output(case, problem, tmp_path, run_darts):
    image, mask, camera = SAMPLE / "image.png", SAMPLE / "mask.png", SAMPLE / "camera.json"
    extra = []
    if case == "not an image":
        image = tmp_path / "image.png"
        image.write_bytes(b"\x89PNG this is not a picture")
    elif case in ("tiny", "blank", "blurred"):
        image = tmp_path / "image.png"
        picture = {"tiny": lambda: Image.new("RGB", (1, 1)), "blank": lambda: Image.new("RGB", (224, 224), (128, 128, 128)),
                   "blurred": lambda: Image.open(SAMPLE / "image.png").filter(ImageFilter.GaussianBlur(3))}[case]()
        picture.save(image)
        mask, camera = None, None
    elif case == "mask size":
        mask = tmp_path / "mask.png"
        Image.fromarray(np.full((100, 100), 255, np.uint8)).save(mask)
    elif case == "camera":
        camera = tmp_path / "camera.json"
        camera.write_text("{ width: 224")
    else:
        extra = ["--category", "poncho"]
    out = tmp_path / "garment.npz"
    options = [*(["--mask", mask] if mask else []), *(["--camera", camera] if camera else [])]
    code, stdout, err = run_darts("reconstruct", image, *options, "-o", out, *extra)
    assert code == 2 and stdout == "" and len(err.strip().splitlines()) == 1 and problem in err, err
    assert not out.exists() and list(tmp_path.glob("*.npz")) == []


def test_a_photograph_alone_is_parsed_and_the_report_says_what_was_seen(run_darts, tmp_path):
    """The portrait (a uniform jacket, framed above the waist) given alone: the person's parsing finds
    a top whose sleeves run out of the picture (a long-sleeve top, the labelling rule for a jacket)
    and no lower garment, which the report says; the report carries what was given (nothing but
    the picture) and what was estimated (the body, the garment's mask and category)."""
    out, report = tmp_path / "garment.npz", tmp_path / "report.json"
    code, stdout, err = run_darts("reconstruct", PORTRAIT, "-o", out, "--report", report, "--edge-length", "0.05")
    assert code == 0, err
    data = json.loads(report.read_text())
    assert data["category"] == "long-sleeve-top" and data["probability"] >= 0.6 and not data["low_confidence"]
    assert set(data["probabilities"]) == {"long-sleeve-top", "short-sleeve-top", "sleeveless-top"}
    assert sum(data["probabilities"].values()) == pytest.approx(1.0, abs=1e-4)
    assert data["given"] == {"category": False, "camera": False, "mask": False, "betas": False}
    assert data["posed"] and data["mask_estimated"] and data["category_from"] == "photo parsing"
    assert data["garment"] == "upper" and [g["kind"] for g in data["outfit"]["garments"]] == ["upper"]
    assert data["outfit"]["garments"][0]["attributes"]["sleeve_beyond_picture"]
    assert any("no lower garment" in note for note in data["outfit"]["notes"])
    assert (data["camera"]["width"], data["camera"]["height"]) == (512, 600) and load_dart(out).category == data["category"]


def test_sharpness_tells_the_sample_from_its_blurred_copies():
    """The held-out sample passes the sharpness limit; blurred by a Gaussian of radius 2 or 3 pixels it does not."""
    from darts.fileio import read_image
    from darts.regress.checks import MIN_SHARPNESS, sharpness

    sample = Image.open(SAMPLE / "image.png").convert("RGB")
    assert sharpness(read_image(SAMPLE / "image.png")) > 5 * MIN_SHARPNESS
    for radius in (2, 3):
        assert sharpness(np.asarray(sample.filter(ImageFilter.GaussianBlur(radius)))) < MIN_SHARPNESS



def _still_motion(path: Path) -> Path:
    """A three-frame AMASS motion: the body standing in its rest pose."""
    save_npz(path, poses=np.zeros((3, 156)), trans=np.tile([0.0, 0.0, 1.0], (3, 1)), betas=np.zeros(16),
             gender=np.array("neutral"), mocap_framerate=np.array(30.0))
    return path


def test_a_photograph_to_an_outfit_folder_that_darts_sim_runs(run_darts, run_sim, tmp_path):
    """-o OUT_DIR writes one DART per garment seen (the portrait: its jacket), outfit.json in layer
    order, report.json; darts-sim OUT_DIR runs it and simulates a few frames on the fitted shape."""
    from darts.outfit_folder import outfit_garments

    folder = tmp_path / "outfit"
    code, stdout, err = run_darts("reconstruct", PORTRAIT, "-o", folder, "--edge-length", "0.05")
    assert code == 0, err
    index = json.loads((folder / "outfit.json").read_text())
    assert index["garments"] == ["long-sleeve-top.npz"] and index["kinds"] == ["upper"]
    assert outfit_garments(folder) == [folder / "long-sleeve-top.npz"]
    dart = load_dart(folder / "long-sleeve-top.npz")
    assert np.allclose(dart.body_betas, index["betas"]) and np.abs(index["betas"]).max() > 0
    report = json.loads((folder / "report.json").read_text())
    assert [g["category"] for g in report["garments"]] == ["long-sleeve-top"]
    assert "darts-sim" in stdout and "note: no lower garment" in stdout
    usd, stats = tmp_path / "sim.usdc", tmp_path / "stats.json"
    code, _, err = run_sim(folder, _still_motion(tmp_path / "still.npz"), "-o", usd, "--settle", "0.1", "--stats", stats,
                           "--quiet")
    assert code == 0, err
    data = json.loads(stats.read_text())
    assert data["stable"] and len(data["frames"]) == 3 and data["max_penetration"] < 0.02


@pytest.mark.slow
def test_darts_sim_runs_an_outfit_folder_in_its_layer_order(run_sim, tmp_path):
    """Two shipped garments written as an outfit folder (pants inner) simulate as the outfit of the
    two given one by one; a folder without outfit.json is one line and exit 2."""
    from darts.outfit_folder import write_outfit_folder

    folder = tmp_path / "outfit"
    garments = [(f"{name}.npz", load_dart(SAMPLE.parent / "garments" / f"{name}.npz")) for name in ("long-pants",
                                                                                                  "short-sleeve-top")]
    write_outfit_folder(folder, garments, {"layers": "inner first"})
    motion, stats = _still_motion(tmp_path / "still.npz"), tmp_path / "stats.json"
    code, _, err = run_sim(folder, motion, "-o", tmp_path / "sim.usdc", "--settle", "0.1", "--stats", stats, "--quiet")
    assert code == 0, err
    assert list(json.loads(stats.read_text())["garments"]) == ["long_pants", "short_sleeve_top"]
    (folder / "outfit.json").unlink()
    code, stdout, err = run_sim(folder, motion, "-o", tmp_path / "again.usdc")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "without outfit.json" in err, err
    assert not (tmp_path / "again.usdc").exists()


def test_an_outfit_folder_takes_no_mask_camera_or_category(run_darts, tmp_path):
    code, stdout, err = run_darts("reconstruct", PORTRAIT, "-o", tmp_path / "outfit", "--category", "long-sleeve-top")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "give -o garment.npz" in err, err
    assert not (tmp_path / "outfit").exists()


@pytest.mark.parametrize("picture", ["noise", "tiny", "blank"])
def test_an_outfit_from_a_bad_photograph_is_one_line_exit_2_and_no_folder(run_darts, tmp_path, picture):
    path = tmp_path / "photo.png"
    size = 1 if picture == "tiny" else 224
    pixels = (np.random.default_rng(1).integers(0, 256, (size, size, 3)) if picture == "noise"
              else np.full((size, size, 3), 200))
    Image.fromarray(pixels.astype(np.uint8)).save(path)
    code, out, err = run_darts("reconstruct", path, "-o", tmp_path / "outfit")
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    expected = {"tiny": "too small", "blank": "too blurred or blank"}.get(picture, "shows no person")
    assert "photo.png: " in err and expected in err, err
    assert not (tmp_path / "outfit").exists()
