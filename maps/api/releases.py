"""API of released map files: list, release a map (optionally distributing it), distribute.

Reading needs layouts:read, releasing and distributing layouts:write (see fleet.api_access).
The file itself is served by `maps.views.release_file` at the release's download link (no
login: vehicles).
"""

from typing import Any

from django.shortcuts import get_object_or_404
from django.urls import reverse
from drf_spectacular.utils import extend_schema
from rest_framework import mixins, serializers, status, viewsets
from rest_framework.decorators import action
from rest_framework.request import Request
from rest_framework.response import Response

from maps.models import Map, MapRelease
from maps.selectors import list_releases
from maps.services import distribute_release, release_map


class MapReleaseSerializer(serializers.ModelSerializer[MapRelease]):
    """A release as the API shows it (without the file; `download` is its staff-facing path)."""

    map = serializers.CharField(source="map.map_id", read_only=True)
    download = serializers.SerializerMethodField()

    class Meta:
        model = MapRelease
        fields = [
            "id",
            "map",
            "number",
            "version",
            "file_format",
            "checksum",
            "size",
            "revision",
            "note",
            "created_at",
            "distributed_at",
            "download",
        ]

    def get_download(self, obj: MapRelease) -> str:
        return reverse("maps:release-file", args=[obj.token, obj.file_name])


class ReleaseInputSerializer(serializers.Serializer[None]):
    """What to release: a map by its mapId, a note, and whether to distribute it at once."""

    map = serializers.CharField(max_length=100)
    note = serializers.CharField(max_length=500, required=False, default="", allow_blank=True)
    distribute = serializers.BooleanField(default=False)


class MapReleaseViewSet(
    mixins.ListModelMixin, mixins.RetrieveModelMixin, viewsets.GenericViewSet[MapRelease]
):
    """Released map files; `POST` releases a map, `POST …/distribute/` distributes one."""

    queryset = list_releases()
    serializer_class = MapReleaseSerializer

    def get_queryset(self) -> Any:
        releases = list_releases()
        map_id = self.request.query_params.get("map")
        return releases if map_id is None else releases.filter(map__map_id=map_id)

    @extend_schema(request=ReleaseInputSerializer, responses={201: MapReleaseSerializer})
    def create(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        data = ReleaseInputSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        layout = get_object_or_404(Map, map_id=data.validated_data["map"])
        release = release_map(
            map=layout,
            user=request.user,
            note=data.validated_data["note"],
            distribute=data.validated_data["distribute"],
        )
        return Response(MapReleaseSerializer(release).data, status=status.HTTP_201_CREATED)

    @extend_schema(request=None, responses={200: MapReleaseSerializer})
    @action(detail=True, methods=["post"])
    def distribute(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        """Make this release the version the map's vehicles must enable."""
        release = distribute_release(release=self.get_object(), user=request.user)
        return Response(MapReleaseSerializer(release).data)
