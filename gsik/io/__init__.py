"""File formats: pose and skeleton YAML, BVH clips, URDF robots, and the atomic file writes they share."""
