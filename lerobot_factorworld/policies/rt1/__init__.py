"""RT-1 for LeRobot: FiLM-EfficientNet image tokens, TokenLearner, block-causal transformer, 256-bin actions."""
