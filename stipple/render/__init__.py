"""The drawing (placeholder, filled in the next step)."""
