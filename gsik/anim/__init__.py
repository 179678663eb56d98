"""Motion built on the solver: walking (gait), scenarios, clip tracking and the Motion container."""
