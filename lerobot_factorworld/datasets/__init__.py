"""Scripted demonstrations as LeRobotDataset v3 episodes annotated with their factor values."""
