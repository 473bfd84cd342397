"""Simulation: plants, controllers, sensors, model error, collisions and scenarios."""
