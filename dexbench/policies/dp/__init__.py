"""Diffusion Policy on low-dimensional state observations."""
