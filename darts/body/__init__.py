"""The SMPL-format body model: ``load_body()`` gives the bundled default or an official file."""
from darts.body.io import export_smpl_npz, load_body
from darts.body.model import BodyModel, BodyOutput
from darts.body.segmentation import PART_NAMES, body_segmentation

__all__ = ["BodyModel", "BodyOutput", "PART_NAMES", "body_segmentation", "export_smpl_npz", "load_body"]
