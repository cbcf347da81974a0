"""Simulated users, objectives and simulated experiments."""
