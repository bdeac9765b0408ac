"""The robot that carries the tool: model, IK branches, reach, configurations, timing."""
