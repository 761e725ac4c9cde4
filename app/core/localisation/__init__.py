"""The robot finds itself (Qt-free): dead reckoning, EKF odometry fusion,
scan pre-processing, ICP scan matching, laser mapping with loop closure,
occupancy grids in ROS map_server format, and a CARMEN log reader.
Seeds 002 (laser mapping) and 003 (EKF odometry fusion)."""
