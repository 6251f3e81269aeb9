"""ROS-free 2.5D simulator (worlds, sensors, engine) and its ROS node.

Layers, each importing only those above it: ``sim_bridge.world`` (data types and
``rasterize``); ``sim_bridge.worlds`` (ground truth, world files, generated houses and
mazes); ``sim_bridge.sensors`` (2D lidar, RGB-D camera), ``sim_bridge.mapping``,
``sim_bridge.navigation`` (planner, navigator), ``sim_bridge.collision``;
``sim_bridge.params`` (:class:`SimParams`); ``sim_bridge.engine``; ``sim_bridge.node``.
Importing the package imports nothing heavy; import the submodules you need.
"""
