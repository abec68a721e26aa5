"""The SMPL-format body model: ``read_body()`` gives its arrays (numpy), ``load_body()`` the posable
``BodyModel`` (torch), of the bundled default or an official file. Names load on first use."""
from darts.lazy import lazy_exports as _lazy_exports

__getattr__, __dir__, __all__ = _lazy_exports(__name__, {
    "BodyArrays": "io", "export_smpl_npz": "io", "load_body": "io", "read_body": "io", "BodyModel": "model",
    "BodyOutput": "model", "PART_NAMES": "segmentation", "body_segmentation": "segmentation"})
