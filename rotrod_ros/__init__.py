"""rotrod_ros: thin rclpy nodes over rotrod_core."""
