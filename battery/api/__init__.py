"""Read API v1 of the battery app."""
