"""REST API v1 of the robots app."""
