"""The ERP API for transport orders: create (idempotent), list, get, cancel, change priority."""

from typing import Any

from django.db.models import Prefetch, QuerySet, prefetch_related_objects
from django.shortcuts import get_object_or_404
from drf_spectacular.utils import (
    OpenApiExample,
    OpenApiResponse,
    extend_schema,
    extend_schema_serializer,
)
from rest_framework import generics, serializers, status
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from maps.models import Station, VehicleType
from orders import selectors, services
from orders.api import idempotency
from orders.api.serializers import TransportOrderSerializer, validate_json_parameters
from orders.models import OrderStep, TransportOrder
from robots.models import Vehicle

CONFLICT = OpenApiResponse(description="Not allowed in the order's current state (`detail`).")
UNPROCESSABLE = OpenApiResponse(description="Well-formed but cannot be carried out (`detail`).")


class UpperCaseChoiceField(serializers.ChoiceField):
    """A choice that also accepts lower case (`?status=new`)."""

    def to_internal_value(self, data: Any) -> Any:
        return super().to_internal_value(str(data).upper())


def _vehicle(serial_number: str) -> Vehicle:
    found = list(Vehicle.objects.filter(serial_number=serial_number)[:2])
    if len(found) != 1:
        problem = "No vehicle" if not found else "Several vehicles have serial number"
        raise serializers.ValidationError({"intended_vehicle": [f"{problem} {serial_number!r}."]})
    return found[0]


def _vehicle_type(type_id: str) -> VehicleType:
    try:
        return VehicleType.objects.get(type_id=type_id)
    except VehicleType.DoesNotExist:
        raise serializers.ValidationError(
            {"vehicle_type": [f"No vehicle type {type_id!r}."]}
        ) from None


class StepInputSerializer(serializers.Serializer[dict[str, Any]]):
    """One stop of a multi-stop order."""

    station = serializers.CharField(max_length=100, help_text="station id")
    operation = UpperCaseChoiceField(choices=OrderStep.Operation.choices)
    action_type = serializers.CharField(
        max_length=100, required=False, help_text="VDA 5050 action type, for operation ACTION"
    )
    parameters = serializers.JSONField(
        required=False, help_text="action parameters as an object of key: value"
    )

    def validate_parameters(self, value: Any) -> Any:
        return validate_json_parameters(value)


class TransportOrderListCreateApi(generics.ListAPIView[TransportOrder]):
    """GET: transport orders, newest first, with filters. POST: create one."""

    serializer_class = TransportOrderSerializer

    @extend_schema_serializer(component_name="OrderFilter")
    class FilterSerializer(serializers.Serializer[dict[str, Any]]):
        status = UpperCaseChoiceField(choices=TransportOrder.Status.choices, required=False)
        vehicle = serializers.CharField(required=False, help_text="serial number")
        vehicle_id = serializers.IntegerField(required=False, min_value=1, max_value=2**62)
        source = serializers.CharField(  # type: ignore[assignment]
            required=False, help_text="station id"
        )
        destination = serializers.CharField(required=False, help_text="station id")
        external_ref = serializers.CharField(required=False)
        created_after = serializers.DateTimeField(required=False)
        created_before = serializers.DateTimeField(required=False)
        finished_after = serializers.DateTimeField(required=False)
        finished_before = serializers.DateTimeField(required=False)

    @extend_schema_serializer(component_name="OrderCreate")
    class InputSerializer(serializers.Serializer[dict[str, Any]]):
        source = serializers.CharField(  # type: ignore[assignment]
            max_length=100,
            required=False,
            help_text="station id of the pickup (a pick → drop order; or give `steps`)",
        )
        destination = serializers.CharField(
            max_length=100, required=False, help_text="station id of the drop"
        )
        steps = StepInputSerializer(
            many=True,
            required=False,
            help_text="the stops in order (instead of source and destination)",
        )
        intended_vehicle = serializers.CharField(
            max_length=100, required=False, help_text="serial number of the only vehicle allowed"
        )
        vehicle_type = serializers.CharField(
            max_length=100, required=False, help_text="layout vehicle type id the vehicle must have"
        )
        metadata = serializers.JSONField(
            required=False, help_text="free JSON object, stored and returned as given"
        )
        sequence = serializers.CharField(
            max_length=100,
            required=False,
            help_text="reference of an order sequence: its orders are done in turn by one vehicle",
        )
        map = serializers.CharField(
            max_length=100, required=False, help_text="map id; needed when station ids repeat"
        )
        priority = serializers.IntegerField(default=0, min_value=-1000, max_value=1000)
        load_id = serializers.CharField(default="", allow_blank=True, max_length=100)
        load_type = serializers.CharField(default="EPAL", max_length=100)
        external_ref = serializers.CharField(default="", allow_blank=True, max_length=200)
        earliest_start = serializers.DateTimeField(required=False, allow_null=True)
        deadline = serializers.DateTimeField(required=False, allow_null=True)

        def validate_metadata(self, value: Any) -> Any:
            return validate_json_parameters(value)

        def validate(self, attrs: dict[str, Any]) -> dict[str, Any]:
            if "steps" in attrs:
                if "source" in attrs or "destination" in attrs:
                    raise serializers.ValidationError(
                        {"steps": ["Give steps or source and destination, not both."]}
                    )
                if not attrs["steps"]:
                    raise serializers.ValidationError({"steps": ["At least one step."]})
            else:
                missing = [f for f in ("source", "destination") if f not in attrs]
                if missing:
                    raise serializers.ValidationError(
                        {f: ["This field is required (or give steps)."] for f in missing}
                    )
            return attrs

    @extend_schema(parameters=[FilterSerializer])
    def get(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        return super().get(request, *args, **kwargs)

    def get_queryset(self) -> QuerySet[TransportOrder]:
        filters = self.FilterSerializer(data=self.request.query_params)
        filters.is_valid(raise_exception=True)
        return selectors.list_transport_orders(filters=filters.validated_data)

    @extend_schema(
        request=InputSerializer,
        parameters=[idempotency.PARAMETER],
        examples=[
            OpenApiExample(
                "Pallet from a pick to a drop station",
                request_only=True,
                value={
                    "source": "PICK-1",
                    "destination": "DROP-3",
                    "load_id": "PAL-0042",
                    "external_ref": "SO-2026-1187",
                    "priority": 5,
                    "deadline": "2030-01-01T10:30:00Z",
                },
            ),
            OpenApiExample(
                "Multi-stop: pick, a custom action, then two drops",
                request_only=True,
                value={
                    "steps": [
                        {"station": "PICK-1", "operation": "PICK"},
                        {
                            "station": "PICK-2",
                            "operation": "ACTION",
                            "action_type": "detectObject",
                            "parameters": {"objectType": "pallet"},
                        },
                        {"station": "DROP-1", "operation": "DROP"},
                    ],
                    "vehicle_type": "sim.SimCarrier",
                    "external_ref": "SO-2026-1188",
                },
            ),
        ],
        responses={
            201: TransportOrderSerializer,
            409: OpenApiResponse(description="The same Idempotency-Key is still in flight."),
            422: UNPROCESSABLE,
        },
    )
    def post(self, request: Request) -> Response:
        return idempotency.idempotent(request, lambda: self._create(request))

    def _create(self, request: Request) -> Response:
        data = self.InputSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        fields = dict(data.validated_data)
        map_id = fields.pop("map", None)
        if "steps" in fields:
            named = {
                f"steps[{i}].station": step["station"] for i, step in enumerate(fields["steps"])
            }
            stations = _stations(named, map_id)
            fields["steps"] = [
                services.StepSpec(
                    station=stations[f"steps[{i}].station"],
                    operation=step["operation"],
                    action_type=step.get("action_type", ""),
                    parameters=step.get("parameters", {}),
                )
                for i, step in enumerate(fields["steps"])
            ]
        else:
            fields.update(_stations({k: fields[k] for k in ("source", "destination")}, map_id))
        if "intended_vehicle" in fields:
            fields["intended_vehicle"] = _vehicle(fields["intended_vehicle"])
        if "vehicle_type" in fields:
            fields["vehicle_type"] = _vehicle_type(fields["vehicle_type"])
        order = services.create_transport_order(created_by=request.user, **fields)
        # Two reads for the answer's steps (with their stations) and events, not one per step:
        # the answer is written before the order commits, so dispatch waits for it.
        prefetch_related_objects(
            [order], Prefetch("steps", OrderStep.objects.select_related("station")), "events"
        )
        return Response(TransportOrderSerializer(order).data, status=status.HTTP_201_CREATED)


def _stations(named: dict[str, str], map_id: str | None) -> dict[str, Station]:
    """The station each request field names (field → station id), read in one query: an
    unknown id, or one on several maps without `map`, is a 400 naming the field."""
    stations = Station.objects.filter(station_id__in=set(named.values())).select_related(
        "map", "node"
    )
    if map_id is not None:
        stations = stations.filter(map__map_id=map_id)
    by_id: dict[str, list[Station]] = {}
    for station in stations:
        by_id.setdefault(station.station_id, []).append(station)
    found: dict[str, Station] = {}
    for field, station_id in named.items():
        matches = by_id.get(station_id, [])
        if not matches:
            raise serializers.ValidationError({field: [f"No station {station_id!r}."]})
        if len(matches) > 1:
            raise serializers.ValidationError(
                {field: [f"{station_id!r} is on several maps: give map."]}
            )
        found[field] = matches[0]
    return found


class TransportOrderDetailApi(generics.RetrieveAPIView[TransportOrder]):
    """One transport order with its event timeline."""

    serializer_class = TransportOrderSerializer
    queryset = TransportOrder.objects.select_related(
        "source__map", "destination", "vehicle", "intended_vehicle", "vehicle_type", "sequence"
    ).prefetch_related("events", "steps__station")


class TransportOrderCancelApi(APIView):
    """Cancel an order: at once while it waits, else the vehicle is asked to stop (the order
    shows `cancel_requested` until the vehicle confirms)."""

    @extend_schema_serializer(component_name="OrderCancel")
    class InputSerializer(serializers.Serializer[dict[str, Any]]):
        reason = serializers.CharField(default="", allow_blank=True, max_length=200)

    @extend_schema(
        request=InputSerializer, responses={200: TransportOrderSerializer, 409: CONFLICT}
    )
    def post(self, request: Request, pk: int) -> Response:
        data = self.InputSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        order = services.cancel_transport_order(
            order=get_object_or_404(TransportOrder, pk=pk),
            reason=data.validated_data["reason"],
            by=request.user,
        )
        return Response(TransportOrderSerializer(order).data)


class TransportOrderPriorityApi(APIView):
    """Change an open order's priority, and its deadline when given (null clears it)."""

    @extend_schema_serializer(component_name="OrderPriority")
    class InputSerializer(serializers.Serializer[dict[str, Any]]):
        priority = serializers.IntegerField(min_value=-1000, max_value=1000)
        deadline = serializers.DateTimeField(required=False, allow_null=True)

    @extend_schema(
        request=InputSerializer,
        responses={200: TransportOrderSerializer, 409: CONFLICT, 422: UNPROCESSABLE},
    )
    def post(self, request: Request, pk: int) -> Response:
        data = self.InputSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        order = services.update_order_priority(
            order=get_object_or_404(TransportOrder, pk=pk),
            priority=data.validated_data["priority"],
            deadline=data.validated_data.get("deadline"),
            change_deadline="deadline" in data.validated_data,
            by=request.user,
        )
        return Response(TransportOrderSerializer(order).data)
