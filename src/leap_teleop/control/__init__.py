"""Robot-agnostic control pieces, no ROS: filters, input checks and the joint servo."""
