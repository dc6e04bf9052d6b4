"""Read API v1 of the maintenance app."""
