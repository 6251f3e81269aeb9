"""Floor-plan prediction: a guess of the occupancy of the map's unknown cells.

* :mod:`.features`: the occupancy grid as the network's input (free / occupied / unknown
  fractions per coarse cell) and the coarse frame it lives in; numpy only.
* :mod:`.model`: the U-Net and its weight file (``.npz``, float32 arrays); the network is
  built with torch, imported only when a model is loaded.
* :mod:`.inference`: :class:`~.inference.FloorPlanPredictor` (map -> probability that each
  coarse cell is free space inside the building) and :func:`~.inference.load_predictor`,
  which says why no predictor is available (torch or the weights missing) instead of
  raising, so the exploration runs on without it.
* :mod:`.gain`: the expected unknown free area a 360-degree sensor would newly see from a
  cell, on the predicted map.
"""
