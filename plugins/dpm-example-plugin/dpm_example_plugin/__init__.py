"""Example dpm plugin package."""
