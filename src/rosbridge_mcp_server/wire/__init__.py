"""The rosbridge v2 protocol without I/O: ops, ids, fragments, inbound decoding, ROS 1 / ROS 2 dialects."""
