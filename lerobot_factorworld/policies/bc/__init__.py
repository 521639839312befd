"""The paper's simulation behaviour-cloning policy for LeRobot: a small CNN (or a frozen pretrained encoder) and an MLP."""
