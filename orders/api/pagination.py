"""Pagination of every API list: limit/offset with bounds."""

from rest_framework.pagination import LimitOffsetPagination
from rest_framework.request import Request


class BoundedLimitOffsetPagination(LimitOffsetPagination):
    """`?limit=&offset=` as DRF does it, but with a largest page (500) and a largest offset, so a
    huge number cannot reach the database (where it would overflow its integer types)."""

    max_limit = 500
    max_offset = 10**9

    def get_offset(self, request: Request) -> int:
        return min(super().get_offset(request), self.max_offset)
