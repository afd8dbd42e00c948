"""File formats: TUM, EuRoC, ROS bags, output folders."""
