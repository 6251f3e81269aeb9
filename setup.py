"""ament_python build of explore_seg (colcon) and plain pip installs."""

import os
from glob import glob

from setuptools import find_packages, setup

PACKAGE = "explore_seg"


def data_tree(folder: str) -> list[tuple[str, list[str]]]:
    """data_files entries installing ``folder`` with its subfolders to share/PACKAGE/folder
    (a data_files entry takes files only, one destination folder each)."""
    return [(f"share/{PACKAGE}/{path}", sorted(os.path.join(path, f) for f in files))
            for path, _dirs, files in sorted(os.walk(folder)) if files]

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test", "test.*", "bench", "scripts"]),
    # The floor-plan predictor's weights (make train-predictor).
    package_data={"explore_seg.core.prediction": ["weights/*.npz"]},
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml", "README.md"]),
        (f"share/{PACKAGE}/config", glob("config/*.yaml") + glob("config/*.rviz")),
    ] + data_tree("worlds"),
    install_requires=["setuptools"],
    extras_require={"test": ["pytest", "pytest-timeout", "open3d-cpu", "scikit-learn",
                             "shapely", "matplotlib"],
                    "ray": ["ray==2.60.0"]},
    zip_safe=True,
    maintainer="explore_seg developers",
    maintainer_email="explore-seg@example.org",
    description="Autonomous exploration with 2D-map segmentation and object costmaps",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "explorer = explore_seg.explorer:main",
            "frontier_detector = explore_seg.frontier_node:main",
            "target_selector = explore_seg.selector_node:main",
            "segmentation = explore_seg.segmentation_node:main",
            "object_costmap = explore_seg.object_costmap_node:main",
            "segment_map = explore_seg.segment_cli:main",
            "sim_bridge = sim_bridge.node:main",
        ],
    },
)
