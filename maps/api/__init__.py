"""REST API v1 of the maps app."""
