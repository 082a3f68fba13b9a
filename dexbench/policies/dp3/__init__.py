"""3D Diffusion Policy (DP3) on point clouds and proprioception."""
