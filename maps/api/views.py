"""API of maps, sites, stations and zones: read-only layout data, zones read and write,
LIF import and export, validation, edge speed limits after zones."""

from typing import Any

from drf_spectacular.types import OpenApiTypes
from drf_spectacular.utils import OpenApiParameter, extend_schema
from rest_framework import status, viewsets
from rest_framework.decorators import action
from rest_framework.parsers import JSONParser, MultiPartParser
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from maps.api.serializers import (
    LifImportInputSerializer,
    MapSerializer,
    SiteSerializer,
    StationSerializer,
    ZoneInputSerializer,
    ZoneSerializer,
)
from maps.models import Map, Site, Station, Zone
from maps.selectors import (
    edge_speed_limits,
    export_map_lif,
    export_site_lif,
    layout_as_dict,
    validate_layout,
)
from maps.services import create_zone, delete_zone, import_lif, update_zone


class MapViewSet(viewsets.ReadOnlyModelViewSet[Map]):
    queryset = Map.objects.select_related("site")
    serializer_class = MapSerializer

    @action(detail=True)
    def layout(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        """Nodes, edges and stations of the map as plain data."""
        return Response(layout_as_dict(map=self.get_object()))

    @action(detail=True)
    def lif(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        """The map as a LIF 1.0 file."""
        layout = self.get_object()
        return _attachment(export_map_lif(map=layout), f"{layout.map_id}.lif.json")

    @action(detail=True)
    def validation(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        """The map's validation findings, errors first."""
        layout = self.get_object()
        findings = validate_layout(map=layout)
        return Response(
            {
                "map": layout.map_id,
                "errors": sum(f.severity == "error" for f in findings),
                "warnings": sum(f.severity == "warning" for f in findings),
                "findings": [f.as_dict() for f in findings],
            }
        )

    @action(detail=True, url_path="speed-limits")
    def speed_limits(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        """Edge id → speed limit (m/s, null: none) after speed zones; closed edges left out."""
        layout = self.get_object()
        return Response({"map": layout.map_id, "edges": edge_speed_limits(map=layout)})


class ZoneViewSet(viewsets.ModelViewSet[Zone]):
    """Zones of the maps: list (filter by ?map=, ?zone_type=, ?enabled=), read; create, change
    and delete with layouts:write (fleet.api_access). Every change takes effect in routing at
    once (the map's revision bumps)."""

    queryset = Zone.objects.select_related("map").prefetch_related("vehicle_types")
    serializer_class = ZoneSerializer

    def get_queryset(self) -> Any:
        zones = super().get_queryset().order_by("map__map_id", "zone_id")
        params = self.request.query_params
        if params.get("map"):
            zones = zones.filter(map__map_id=params["map"])
        if params.get("zone_type"):
            zones = zones.filter(zone_type=params["zone_type"])
        if params.get("enabled") in ("true", "false"):
            zones = zones.filter(enabled=params["enabled"] == "true")
        return zones

    @extend_schema(request=ZoneInputSerializer, responses={201: ZoneSerializer})
    def create(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        data = _valid(ZoneInputSerializer(data=request.data))
        zone = create_zone(**data)
        return Response(ZoneSerializer(zone).data, status=status.HTTP_201_CREATED)

    @extend_schema(request=ZoneInputSerializer, responses=ZoneSerializer)
    def update(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        zone = self.get_object()
        partial = kwargs.get("partial", False)
        data = _valid(ZoneInputSerializer(zone, data=request.data, partial=partial))
        data.pop("map", None)  # a zone stays on its map
        zone = update_zone(zone=zone, **data)
        return Response(ZoneSerializer(zone).data)

    @extend_schema(request=ZoneInputSerializer, responses=ZoneSerializer)
    def partial_update(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        return self.update(request, *args, partial=True, **kwargs)

    def destroy(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        delete_zone(zone=self.get_object())
        return Response(status=status.HTTP_204_NO_CONTENT)


def _valid(serializer: Any) -> dict[str, Any]:
    serializer.is_valid(raise_exception=True)
    return dict(serializer.validated_data)


class SiteViewSet(viewsets.ReadOnlyModelViewSet[Site]):
    queryset = Site.objects.prefetch_related("maps")
    serializer_class = SiteSerializer

    @action(detail=True)
    def lif(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        """Every map of the site as one LIF 1.0 file."""
        site = self.get_object()
        return _attachment(export_site_lif(site=site), f"{site.site_id}.lif.json")


class StationViewSet(viewsets.ReadOnlyModelViewSet[Station]):
    queryset = Station.objects.select_related("map", "node")
    serializer_class = StationSerializer


class LifImportApi(APIView):
    """POST a LIF file (multipart field `file`, or the JSON itself as the body); layouts:write.

    `site` and `replace` come from the query string or form fields. 201 with the import report,
    or 422 with the report of every problem (nothing written).
    """

    parser_classes = [MultiPartParser, JSONParser]

    @extend_schema(
        request={
            "application/json": OpenApiTypes.OBJECT,
            "multipart/form-data": OpenApiTypes.OBJECT,
        },
        parameters=[
            OpenApiParameter("site", OpenApiTypes.STR, description="site the layout belongs to"),
            OpenApiParameter("replace", OpenApiTypes.BOOL, description="replace a layout"),
        ],
        responses={201: OpenApiTypes.OBJECT, 422: OpenApiTypes.OBJECT},
        summary="Import a LIF file (staff only)",
    )
    def post(self, request: Request) -> Response:
        params = LifImportInputSerializer(data={**request.query_params.dict(), **_form(request)})
        params.is_valid(raise_exception=True)
        upload = request.FILES.get("file")
        source = upload.read() if upload is not None else request.data
        report = import_lif(
            source=source,
            site_id=params.validated_data["site"],
            replace=params.validated_data["replace"],
            file_name=upload.name if upload is not None and upload.name else "",
        )
        code = status.HTTP_201_CREATED if report.ok else status.HTTP_422_UNPROCESSABLE_ENTITY
        return Response(report.as_dict(), status=code)


def _form(request: Request) -> dict[str, Any]:
    if request.FILES or request.content_type.startswith("multipart/"):
        return {k: request.data[k] for k in ("site", "replace") if k in request.data}
    return {}


def _attachment(document: dict[str, Any], file_name: str) -> Response:
    response = Response(document)
    response["Content-Disposition"] = f'attachment; filename="{file_name}"'
    return response
