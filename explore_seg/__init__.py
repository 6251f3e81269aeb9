"""explore_seg: autonomous exploration with 2D-map segmentation and object costmaps."""

__version__ = "0.1.0"
