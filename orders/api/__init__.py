"""REST API v1 of the orders app."""
