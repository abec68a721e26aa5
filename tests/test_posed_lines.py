"""The posed line regressor's geometry (``darts.regress.posed_lines``): lines posed and taken back,
the crop's camera, the crop's picture."""
from __future__ import annotations

import numpy as np

from darts.camera import Camera
from darts.photo.crop import Crop
from darts.regress.data import initial_lines
from darts.regress.posed_lines import MARGIN, garment_crop, posed, posing_of, root_free, unposed


def _walk_pose(body) -> np.ndarray:
    from darts.motion.amass import load_motion
    from darts.shipped import resolve_motion

    return load_motion(resolve_motion("walk")).model_pose(body.num_joints)[20]


def test_lines_posed_and_taken_back_return_where_they_were(body):
    """F_g posed at a walk frame comes back to itself; lines moved 6 cm down the body at rest
    (a longer hem), posed with the skinning of where they went, come back there (0.5 mm on average)
    through the skinning of where they started, corrected once at the point found."""
    pose, betas = root_free(_walk_pose(body)), np.zeros(8)
    start = initial_lines("long-sleeve-top")
    posing = posing_of(body, pose, betas, start)
    seen = posed(posing, start)
    assert np.abs(seen - start).max() > 0.05  # the pose moved them
    assert np.abs(unposed(body, pose, betas, posing, seen) - start).max() < 1e-9
    moved = start + [0.0, -0.06, 0.0]
    seen_moved = posed(posing_of(body, pose, betas, moved), moved)
    back = unposed(body, pose, betas, posing, seen_moved)
    first = np.linalg.solve(posing.linear.numpy(), (seen_moved.reshape(-1, 3) - posing.offset.numpy())[..., None])[..., 0]
    error = np.linalg.norm(back - moved, axis=-1)
    once = np.linalg.norm(first.reshape(moved.shape) - moved, axis=-1)
    # measured: 0.18 mm mean, 4.5 mm at most; through the starting skinning alone 2.1 and 13 mm
    assert error.mean() < 5e-4 and error.max() < 6e-3 and error.mean() < once.mean() / 5
    assert np.array_equal(root_free(pose), pose) and root_free(_walk_pose(body))[0].tolist() == [0.0, 0.0, 0.0]


def test_the_crop_sees_through_its_cropped_camera():
    """A point's pixel in the cropped camera is its pixel in the picture moved and scaled with the
    crop; the crop of a mask's box keeps the mask inside it with the margin around it."""
    camera = Camera.look_at([0.3, 1.2, 2.5], [0.0, 1.0, 0.0], 320, 240, 300.0)
    mask = np.zeros((240, 320), bool)
    mask[60:140, 150:190] = True
    crop = Crop.around(mask, MARGIN)
    x, y, side = crop.x, crop.y, crop.side
    assert side == 80 * 1.4 and (x, y) == (170 - 56, 100 - 56)
    points = np.random.default_rng(0).normal([0, 1, 0], 0.2, (20, 3))
    pixels, _ = camera.project(points)
    cropped, _ = crop.camera(camera, 224).project(points)
    assert np.allclose(cropped, (pixels - [x, y]) * 224 / side, atol=1e-9)


def test_the_crop_shows_the_garment_alone_on_grey():
    image = np.zeros((100, 100, 3), np.uint8)
    image[..., 0] = 200
    mask = np.zeros((100, 100), bool)
    mask[30:70, 40:60] = True
    crop = garment_crop(image, mask, Crop.around(mask, MARGIN), 56)
    inside = crop[..., 0] == 200
    # the box is 56 px square (40 px and 20 % on each side) at one pixel per pixel: 20 x 40 of it garment
    assert crop.shape == (56, 56, 3) and np.all(crop[~inside] == 128)
    assert abs(int(inside.sum()) - 20 * 40) <= 60
