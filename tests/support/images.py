"""A check of the pictures a run writes, shared by tests/test_plots.py and tests/test_compare.py."""

from pathlib import Path

import matplotlib.image

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def assert_png(path: Path) -> None:
    """A readable, non-blank PNG of at least 500 x 300 pixels."""
    assert path.is_file(), path
    assert path.read_bytes()[:8] == PNG_MAGIC, path
    img = matplotlib.image.imread(path)
    assert img.shape[0] > 300 and img.shape[1] > 500, (path, img.shape)
    assert float(img[..., :3].std()) > 0.01, f"{path.name} is blank"
