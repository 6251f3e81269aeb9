"""ROS-free algorithms on numpy. Nothing in this package may import rclpy or ROS messages."""
