"""ROS-free 2.5D simulator (worlds, sensors, engine) and its ROS node.

``sim_bridge.world`` holds the data types, ``sim_bridge.worlds`` loading, generation and
ground-truth rasters, ``sim_bridge.sensors`` the 2D lidar and the RGB-D camera. Importing
the package imports nothing heavy; import the submodules you need.
"""
