"""The photograph front end (darts.photo): the person detector's anchors and decoding, the landmark
region's geometry, a person found in a real photograph and none in pictures without one, and
`darts reconstruct` refusing a picture without a person in one clean line."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from PIL import Image

from darts.photo.detector import Detection, anchors, decode
from darts.photo.person import LANDMARKS, find_person

SAMPLE_DATA = Path(__import__("matplotlib").get_data_path()) / "sample_data"
PORTRAIT = SAMPLE_DATA / "grace_hopper.jpg"  # a half-length portrait, 512 x 600
GIFT_BOX = SAMPLE_DATA / "Minduka_Present_Blue_Pack.png"


def _picture(path: Path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGB"))


def test_anchors_tile_the_input_in_the_models_order():
    """2,254 anchors: 28 x 28 cells of stride 8 with 2 anchors each, 14 x 14 of stride 16 with 2, then
    7 x 7 of stride 32 with 6 (three layers share it); centres of cells, row by row."""
    centres = anchors()
    assert centres.shape == (2254, 2)
    assert np.allclose(centres[0], [0.5 / 28, 0.5 / 28]) and np.allclose(centres[1], centres[0])
    assert np.allclose(centres[2], [1.5 / 28, 0.5 / 28])
    assert np.allclose(centres[1568], [0.5 / 14, 0.5 / 14]) and np.allclose(centres[1960:1966], [0.5 / 7, 0.5 / 7])
    assert np.allclose(centres[-1], [6.5 / 7, 6.5 / 7])


def test_decode_undoes_the_letterbox_and_merges_overlapping_detections():
    """Two anchors of one cell predicting the same box merge into one detection (weighted by score);
    its box and keypoints come back in the pixels of a 448 x 224 picture (letterboxed: scale 1/2,
    56 pixels of padding above and below)."""
    regression = np.zeros((2254, 12), np.float32)
    logits = np.full(2254, -20.0, np.float32)
    cell = 28 * 10 + 14  # stride-8 cell (row 10, column 14): centre (116, 84) input pixels
    for anchor, logit in ((2 * cell, 3.0), (2 * cell + 1, 1.0)):
        regression[anchor] = [4.0, -2.0, 40.0, 20.0, 0.0, 10.0, 0.0, -30.0, 0, 0, 0, 0]
        logits[anchor] = logit
    found = decode(regression, logits, 448, 224)
    assert len(found) == 1 and found[0].score == pytest.approx(1 / (1 + np.exp(-3.0)), rel=1e-5)
    centre_input = np.array([116.0 + 4.0, 84.0 - 2.0])
    to_picture = lambda p: (p - [0.0, 56.0]) * 2.0  # noqa: E731
    assert np.allclose(found[0].box, [*to_picture(centre_input - [20, 10]), *to_picture(centre_input + [20, 10])], atol=1e-3)
    assert np.allclose(found[0].keypoints[0], to_picture(np.array([116.0, 94.0])), atol=1e-3)
    assert np.allclose(found[0].keypoints[1], to_picture(np.array([116.0, 54.0])), atol=1e-3)
    assert decode(regression, np.full(2254, -20.0, np.float32), 448, 224) == []


def test_the_region_stands_the_body_up_and_maps_crop_pixels_back():
    """Keypoint 1 to the right of keypoint 0 (a body lying along +x) gives a region turned by a
    quarter turn whose "up" points along +x; a dot drawn on the picture lands in the 256-pixel crop
    at the place ``to_picture`` maps back to it (within a pixel)."""
    detection = Detection(0.9, np.zeros(4), np.array([[200.0, 150.0], [280.0, 150.0], [0, 0], [0, 0]]))
    region = detection.region()
    assert region.rotation == pytest.approx(np.pi / 2) and region.side == pytest.approx(2 * 80 * 1.25)
    assert np.allclose(region.to_picture(np.array([[0.5, 0.0]])), [[200.0 + 100.0, 150.0]])  # crop's top: +x
    picture = np.zeros((300, 400, 3), np.uint8)
    picture[118:123, 248:253] = 255  # a dot around (250.5, 120.5) pixels
    crop = np.asarray(Image.fromarray(picture).transform((256, 256), Image.AFFINE, region.affine(256), Image.BILINEAR))
    rows, cols = np.nonzero(crop[..., 0] > 100)
    centre = np.array([cols.mean() + 0.5, rows.mean() + 0.5]) / 256
    assert np.linalg.norm(region.to_picture(centre[None])[0] - [250.5, 120.5]) < 1.0


def test_the_person_in_a_photograph():
    """In the portrait: a person (presence over 0.9), her face above her shoulders, her left
    shoulder on the picture's right (she faces the camera), both shoulders visible and inside her
    mask, which covers the middle of the picture and not its top corners."""
    picture = _picture(PORTRAIT)
    person = find_person(picture)
    assert person is not None and person.presence > 0.9 and person.detection.score > 0.5
    nose, left, right = (person.point(n) for n in ("nose", "left_shoulder", "right_shoulder"))
    assert nose[1] < min(left[1], right[1]) - 50 and left[0] > nose[0] > right[0]
    assert person.visibility[[LANDMARKS.index("left_shoulder"), LANDMARKS.index("right_shoulder")]].min() > 0.9
    mask = person.mask
    assert mask.shape == picture.shape[:2]
    for x, y in (nose, left, right):
        assert mask[int(min(y, 599)), int(x)] > 0.5
    assert mask[:40, :40].mean() < 0.1 and mask[:40, -40:].mean() < 0.1
    assert np.abs(person.world[LANDMARKS.index("nose")]).max() < 1.5  # metres about the hips
    record = person.as_dict()
    assert set(record["landmarks_px"]) == set(LANDMARKS) and json.dumps(record)


def test_a_person_found_in_the_mirror_image_is_mirrored_back():
    """The portrait's person found in its mirror image and mirrored back lands where she is found
    directly: her left shoulder on the picture's right again, the landmarks within a few crop pixels,
    her world x (right) the same sign, the mask on the same pixels. The landmark model's read of a
    region and of its mirror differ by 1.4-3.3 of its 256 crop pixels (median over the landmarks; six
    posed renders, no bias in x), here 1.7 (13 picture pixels: the half-length portrait's region is 2,053 pixels wide)."""
    from darts.photo.person import _find_person_once, _mirrored

    picture = _picture(PORTRAIT)
    direct = find_person(picture)
    back = _mirrored(_find_person_once(np.ascontiguousarray(picture[:, ::-1])), picture.shape[1])
    seen = (direct.visibility > 0.5) & (back.visibility > 0.5)
    assert seen[[LANDMARKS.index("left_shoulder"), LANDMARKS.index("right_shoulder")]].all()
    crop_pixel = direct.region.side / 256
    assert np.median(np.linalg.norm(direct.landmarks - back.landmarks, axis=1)[seen]) < 4 * crop_pixel
    assert back.point("left_shoulder")[0] > back.point("nose")[0] > back.point("right_shoulder")[0]
    left = LANDMARKS.index("left_shoulder")
    assert np.sign(back.world[left, 0]) == np.sign(direct.world[left, 0])
    a, b = direct.mask > 0.5, back.mask > 0.5
    assert (a & b).sum() / (a | b).sum() > 0.9
    assert np.allclose(back.region.to_picture(np.array([[0.5, 0.5]])), back.region.centre)
    assert np.all(back.detection.box[:2] < back.detection.box[2:])


def test_the_mirror_image_is_read_when_the_picture_holds_nobody(monkeypatch):
    """A picture where the detector finds nobody is read once more mirrored, at the first rule only
    (no weaker candidates), and the person found there comes back mirrored."""
    import darts.photo.person as person_module

    calls = []
    found = SimpleNamespace(mirrored=True)

    def once(image, candidates=True):
        calls.append((image[0, 0, 0], candidates))
        return found if image[0, 0, 0] == 1 else None

    monkeypatch.setattr(person_module, "_find_person_once", once)
    monkeypatch.setattr(person_module, "_mirrored", lambda person, width: (person, width))
    picture = np.zeros((10, 30, 3), np.uint8)
    picture[0, -1] = 1  # the mirror image's first pixel
    assert person_module.find_person(picture) == (found, 30)
    assert calls == [(0, True), (1, False)]
    picture[0, -1] = 0
    assert person_module.find_person(picture) is None


@pytest.mark.parametrize("name", ["noise", "gift box", "grey"])
def test_no_person_in_pictures_without_one(name):
    picture = {"noise": lambda: np.random.default_rng(0).integers(0, 256, (224, 224, 3), dtype=np.uint8),
               "gift box": lambda: _picture(GIFT_BOX),
               "grey": lambda: np.full((300, 200, 3), 128, np.uint8)}[name]()
    assert find_person(picture) is None


@pytest.mark.parametrize("name", ["logo", "retina", "chelsea"])
def test_no_person_in_the_pictures_nearest_to_one(name):
    """scikit-image's samples (installed with gpytoolbox) that the detector's weaker candidates take
    for a person: its logo (presence 0.97, crispness 0.61), the retina (presence 0.74), a cat."""
    data = pytest.importorskip("skimage.data")
    picture = np.ascontiguousarray(np.asarray(getattr(data, name)())[..., :3])
    assert find_person(picture) is None


def test_a_weaker_detection_is_taken_only_with_a_sure_person(monkeypatch):
    """When the best detection's region holds no person the next candidates are tried, and one is
    taken only at a presence of 0.9 with a crisp mask."""
    import darts.photo.person as person_module

    def candidate(score, presence, mask_value):
        mask = np.zeros((40, 40), np.float32)
        mask[10:30, 15:25] = mask_value
        return score, presence, mask

    def run(candidates):
        detections = {c[0]: c for c in candidates}
        # the detector's outputs stand for the candidates; decoding keeps those at the bar asked for
        monkeypatch.setattr(person_module, "_detector_outputs", lambda image: (candidates,))
        monkeypatch.setattr(person_module, "decode", lambda found, min_score=0.5: [
            SimpleNamespace(score=c[0]) for c in found if c[0] >= min_score])
        monkeypatch.setattr(person_module, "person_in", lambda image, d: SimpleNamespace(
            presence=detections[d.score][1], mask=detections[d.score][2], score=d.score))
        return person_module.find_person(np.zeros((40, 40, 3), np.uint8))

    assert run([candidate(0.6, 0.1, 1.0), candidate(0.4, 0.99, 1.0)]).score == 0.4
    assert run([candidate(0.6, 0.95, 0.3)]).score == 0.6  # the best detection keeps its own rule
    assert run([candidate(0.6, 0.1, 1.0), candidate(0.4, 0.99, 0.3)]) is None  # a soft mask
    assert run([candidate(0.6, 0.1, 1.0), candidate(0.4, 0.85, 1.0)]) is None  # presence under 0.9
    assert run([candidate(0.6, 0.1, 1.0), candidate(0.2, 0.99, 1.0)]) is None  # scores under 0.25


@pytest.mark.slow
def test_reconstruct_refuses_a_picture_without_a_person_in_one_line(tmp_path):
    """A separate process, so that what the model runtime prints on the process's stderr is seen:
    the gift box (which the classifier calls a short-sleeve top at 83 %) is one line, exit 2,
    nothing written."""
    out = tmp_path / "garment.npz"
    done = subprocess.run([sys.executable, "-m", "darts.cli.main", "reconstruct", str(GIFT_BOX), "-o", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 2 and done.stdout == "", done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and "shows no person" in done.stderr, done.stderr
    assert "Minduka_Present_Blue_Pack.png" in done.stderr and not out.exists() and list(tmp_path.iterdir()) == []


def test_a_picture_without_a_person_goes_on_only_when_asked(run_darts, tmp_path):
    """With --accept-low-confidence the noise picture is reconstructed; the report says no person
    was found and that the answer is of low confidence."""
    image, out, report = tmp_path / "noise.png", tmp_path / "garment.npz", tmp_path / "report.json"
    Image.fromarray(np.random.default_rng(0).integers(0, 256, (224, 224, 3), dtype=np.uint8)).save(image)
    code, stdout, err = run_darts("reconstruct", image, "-o", out, "--report", report, "--accept-low-confidence",
                                  "--edge-length", "0.05")
    assert code == 0 and "low confidence, accepted" in stdout, err
    data = json.loads(report.read_text())
    assert data["person"] is None and data["person_looked_for"] and data["low_confidence"] and out.exists()


def _render_body(body, pose: np.ndarray, betas: np.ndarray, camera, worn=()) -> tuple[np.ndarray, np.ndarray]:
    """A picture of ``body`` posed by ``pose`` [J,3] and ``betas`` wearing ``worn``, and its joints [J,3]."""
    from darts.photo.synthetic import posed_body, render_person

    vertices, joints, _ = posed_body(body, pose, betas)
    return render_person(camera, vertices, body.faces, worn), joints


def test_the_fitted_body_finds_a_known_pose_and_camera():
    """The default body, shaped (three betas) and posed (turned 29 degrees, arms lowered, an elbow
    and a hip bent), rendered through a known camera: the person is found and the fitted body's
    joints project within a median 6 pixels (of 256) of the true ones, its turn within 0.2 rad, its
    landmarks within 4 pixels of the detected ones; the fitted camera of the rest-posed body puts
    the pelvis where the posed one is."""
    import torch

    from darts.body.io import load_body
    from darts.camera import Camera
    from darts.photo.fit import fit_body

    body = load_body(None)
    betas = np.zeros(body.num_betas)
    betas[:3] = [0.8, -0.5, 0.3]
    pose = np.zeros((body.num_joints, 3))
    pose[0], pose[1], pose[16], pose[17], pose[18] = [0, 0.5, 0], [0.3, 0, 0.1], [0, 0, -1.1], [0, 0, 1.1], [0, -0.6, 0]
    camera = Camera.look_at([0.0, -0.2, 3.2], [0.0, -0.25, 0.0], 256, 256, 256.0)
    picture, joints = _render_body(body, pose, betas, camera)
    person = find_person(picture)
    assert person is not None and person.presence > 0.9
    fit = fit_body(person, body, 256, 256)
    posed = body.to(torch.float64)(torch.tensor(fit.pose)[None], torch.tensor(fit.betas)[None]).joints[0].numpy()
    error = np.linalg.norm(fit.posed_camera.project(posed[:22])[0] - camera.project(joints[:22])[0], axis=1)
    assert np.median(error) < 6.0, error
    assert abs(fit.pose[0, 1] - 0.5) < 0.2 and fit.landmark_error_px < 4.0 and fit.landmarks_used >= 12
    pelvis_rest = body.shaped(fit.betas[None])[1][0, 0].double().numpy()
    assert np.allclose(fit.camera.project(pelvis_rest[None])[0], fit.posed_camera.project(posed[:1])[0], atol=1e-6)
    assert json.dumps(fit.as_dict())


def test_a_photographs_report_carries_the_person_and_the_fitted_body(run_darts, tmp_path):
    """The portrait given alone (accepted at low confidence): the report holds the person (nose and
    shoulders seen) and the body fitted to her, within 10 pixels of her landmarks."""
    out, report = tmp_path / "garment.npz", tmp_path / "report.json"
    code, stdout, err = run_darts("reconstruct", PORTRAIT, "-o", out, "--report", report, "--accept-low-confidence",
                                  "--edge-length", "0.05")
    assert code == 0, err
    data = json.loads(report.read_text())
    assert data["person"]["visibility"]["nose"] > 0.9 and data["person"]["visibility"]["left_shoulder"] > 0.9
    assert data["body_fit"]["landmark_error_px"] < 10 and len(data["body_fit"]["betas"]) == 8
    assert data["body_fit"]["translation_m"][2] > 0 and "body_fit_s" in data["times"] and "person_s" in data["times"]


def test_a_garment_on_a_posed_person_is_fitted_through_the_pose():
    """A short-sleeve top made 10 cm longer with sleeves 6 cm longer, worn (skinned) by the default
    body turned 29 degrees with its arms lowered, rendered with its mask; `reconstruct` with the
    mask and no camera finds the person, fits the body, regresses the lines on the posed body and
    fits the template through that pose: its cuffs come to the true ones (0.8 and 2.5 cm off
    against 6.1 cm for the template's), and the result, posed the same way and seen by the fitted
    camera, covers the mask better than the undeformed template on the fitted body does (IoU 0.831
    against 0.751)."""
    import torch

    from darts.body.io import load_body
    from darts.camera import Camera
    from darts.crdl.deform import deform_dart, weld_garment
    from darts.crdl.posed import Posing
    from darts.crdl.targets import edit_targets
    from darts.dart.build import make_dart
    from darts.geometry.loops import feature_lines
    from darts.raycast import cast
    from darts.regress.pipeline import reconstruct
    from darts.templates.defaults import DATASET_EASE

    body = load_body(None)
    pose = np.zeros((body.num_joints, 3))
    pose[0], pose[16], pose[17] = [0, 0.5, 0], [0, 0, -1.0], [0, 0, 1.0]
    camera = Camera.look_at([0.0, -0.2, 3.2], [0.0, -0.25, 0.0], 256, 256, 256.0)
    template = make_dart("short-sleeve-top", body, edge_length=0.04, ease=DATASET_EASE)  # the reconstruction's cut
    welded = weld_garment(template)
    longer, _ = deform_dart(template, body, edit_targets("short-sleeve-top", welded.vertices, welded.lines,
                                                        [("hem", 0.10), ("sleeve", 0.06)]), clearance=0.006)
    truth = weld_garment(longer)
    worn = Posing.of(body, pose, None, welded.vertices)(torch.as_tensor(truth.vertices)).numpy()
    picture, _ = _render_body(body, pose, np.zeros(body.num_betas), camera, [(worn, welded.faces)])
    mask = cast(camera, [(body.to(torch.float64)(torch.tensor(pose)[None]).vertices[0].numpy(), body.faces),
                         (worn, welded.faces)], 1).which.reshape(256, 256) == 1
    result = reconstruct(picture, body, "short-sleeve-top", None, mask, edge_length=0.04)
    report = result.report
    assert report["posed"] and report["lines_from"] == "posed regressor" and report["body_fit"]["landmark_error_px"] < 5
    fit_pose = np.asarray(report["body_fit"]["pose_axis_angle"])
    betas = np.asarray(report["body_fit"]["betas"])
    posed_camera = Camera.from_dict(report["body_fit"]["posed_camera"])
    assert np.array_equal(result.mask, mask)

    def iou(dart) -> float:
        mesh = weld_garment(dart)
        vertices = Posing.of(body, fit_pose, betas, mesh.vertices)(torch.as_tensor(mesh.vertices)).numpy()
        render = cast(posed_camera, [(vertices, mesh.faces)], 1).which.reshape(256, 256) == 0
        return float((render & mask).sum() / (render | mask).sum())

    template = make_dart("short-sleeve-top", body, betas=betas, edge_length=0.04, ease=DATASET_EASE)  # on the fitted body
    assert iou(result.dart) > iou(template) + 0.04 and iou(result.dart) > 0.8  # measured 0.831 against 0.751
    welded_template = weld_garment(template)
    true_lines, template_lines = feature_lines(truth, truth.vertices), feature_lines(welded_template, welded_template.vertices)
    for cuff in ("left_cuff", "right_cuff"):
        regressed = np.asarray(report["lines"][cuff])
        off = np.linalg.norm(regressed[:, None] - true_lines[cuff][None], axis=2).min(1).mean()
        template_off = np.linalg.norm(template_lines[cuff][:, None] - true_lines[cuff][None], axis=2).min(1).mean()
        assert off < 0.5 * template_off, (cuff, off, template_off)


def test_a_crop_around_the_person_maps_back_onto_the_picture():
    """A disc drawn on a 300 x 200 picture, cropped around itself and drawn back, covers itself (IoU > 0.95)."""
    from darts.photo.garment_net import SIZE, network_input, person_crop

    rows, cols = np.mgrid[:200, :300]
    disc = ((cols - 180) ** 2 + (rows - 90) ** 2 < 40 ** 2).astype(np.float32)
    crop = person_crop(disc)
    assert crop.side == pytest.approx(80 * 1.2, abs=2)
    picture = np.repeat((disc * 255).astype(np.uint8)[..., None], 3, 2)
    x = network_input(crop, picture, disc)
    assert x.shape == (4, SIZE, SIZE) and float(x[3].max()) == pytest.approx(1.0)
    back = crop.to_picture(x[3].numpy(), 300, 200) > 0.5
    assert (back & (disc > 0)).sum() / (back | (disc > 0)).sum() > 0.95


@pytest.mark.slow
def test_the_garment_network_learns_a_handful_of_masks_and_categories():
    """Four crops with a bright rectangle (the "garment") in different places, of two categories:
    a few dozen Adam steps fit their masks (IoU > 0.8) and categories."""
    import torch

    from darts.photo.garment_net import SIZE, GarmentNet

    torch.manual_seed(0)
    x = torch.rand(4, 4, SIZE, SIZE) * 0.3
    masks = torch.zeros(4, SIZE, SIZE, dtype=torch.bool)
    for k, (r, c) in enumerate([(10, 10), (40, 20), (20, 50), (50, 50)]):
        masks[k, r:r + 30, c:c + 25] = True
        x[k, :3, r:r + 30, c:c + 25] += 0.6
    labels = torch.tensor([0, 1, 0, 1])
    net = GarmentNet(categories=2, width=8)
    optimiser = torch.optim.Adam(net.parameters(), lr=5e-3)
    for _ in range(80):
        mask_logits, category_logits = net(x)
        loss = (torch.nn.functional.binary_cross_entropy_with_logits(mask_logits[:, 0], masks.float())
                + torch.nn.functional.cross_entropy(category_logits, labels))
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
    net.eval()
    with torch.no_grad():
        mask_logits, category_logits = net(x)
    found = mask_logits[:, 0] > 0
    assert float(((found & masks).sum((1, 2)) / (found | masks).sum((1, 2))).min()) > 0.8
    assert torch.equal(category_logits.argmax(1), labels)


def test_the_body_fits_adam_is_torchs():
    """darts.photo.fit.Adam (written out to spare torch's optimiser's import) takes the same steps as
    torch.optim.Adam, to the bit, over 300 steps of a non-convex loss."""
    import torch

    from darts.photo.fit import Adam

    torch.manual_seed(0)
    ours = torch.randn(5, dtype=torch.float64, requires_grad=True)
    theirs = ours.detach().clone().requires_grad_(True)
    steppers = [(ours, Adam([ours], lr=0.02)), (theirs, torch.optim.Adam([theirs], lr=0.02))]
    for _ in range(300):
        for x, optimiser in steppers:
            x.grad = None
            (((x - torch.arange(5.0, dtype=torch.float64)) ** 4).sum() + x.sin().sum()).backward()
            optimiser.step()
    assert torch.equal(ours, theirs)


def test_photographs_are_read_as_a_viewer_shows_them(tmp_path):
    """A JPEG whose EXIF orientation is 6 (stored sideways, shown turned 90 degrees clockwise) is
    read upright; a 16-bit grey PNG is scaled to 8 bits, not clipped to white."""
    from PIL import Image

    from darts.fileio import read_image

    stored = np.zeros((40, 60, 3), np.uint8)
    stored[:, :10] = 255  # a white band along the stored picture's left edge
    picture = Image.fromarray(stored)
    exif = picture.getexif()
    exif[0x0112] = 6
    picture.save(tmp_path / "turned.jpg", exif=exif.tobytes(), quality=95)
    shown = read_image(tmp_path / "turned.jpg")
    assert shown.shape == (60, 40, 3) and shown[:8].mean() > 240 and shown[-8:].mean() < 15
    ramp = np.linspace(0, 65535, 64 * 64).reshape(64, 64).astype(np.uint16)
    Image.fromarray(ramp).save(tmp_path / "grey16.png")
    grey = read_image(tmp_path / "grey16.png", "L")
    assert grey.min() == 0 and grey.max() == 255 and abs(grey.mean() - 127.5) < 1
    assert np.abs(grey.astype(float) - ramp / 257.0).max() <= 0.5 + 1e-9
