"""Policies: the shared protocol, Diffusion Policy, DP3, the scripted-expert and RL policies."""
