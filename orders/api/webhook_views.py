"""Webhook subscriptions of the calling integration client: list, create, show, delete, ping."""

from typing import Any

from django.contrib.auth.models import User
from django.shortcuts import get_object_or_404
from drf_spectacular.utils import OpenApiResponse, extend_schema, extend_schema_serializer
from rest_framework import exceptions, serializers, status
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from orders import services
from orders.api.serializers import (
    WebhookSubscriptionCreatedSerializer,
    WebhookSubscriptionSerializer,
)
from orders.models import IntegrationClient, WebhookSubscription
from orders.models.webhooks import EVENT_TYPES


def _client(request: Request) -> IntegrationClient:
    user = request.user if isinstance(request.user, User) else None
    client = IntegrationClient.objects.filter(user=user, is_active=True).first()
    if client is None:
        raise exceptions.PermissionDenied(
            "Webhook subscriptions belong to integration clients: use a client's API token."
        )
    return client


def _subscription(request: Request, pk: int) -> WebhookSubscription:
    return get_object_or_404(WebhookSubscription, pk=pk, client=_client(request))


class WebhookSubscriptionListCreateApi(APIView):
    """GET: the client's subscriptions. POST: subscribe to events; the answer carries the secret
    for checking the `X-Fleet-Signature` header, shown only this once."""

    @extend_schema_serializer(component_name="WebhookSubscriptionCreate")
    class InputSerializer(serializers.Serializer[dict[str, Any]]):
        url = serializers.URLField(max_length=500)
        events = serializers.ListField(
            child=serializers.CharField(max_length=50),
            min_length=1,
            max_length=50,
            help_text="event types (" + ", ".join(EVENT_TYPES) + '), "order.*" or "*"',
        )
        description = serializers.CharField(default="", allow_blank=True, max_length=200)
        own_orders_only = serializers.BooleanField(default=False)

    @extend_schema(responses=WebhookSubscriptionSerializer(many=True))
    def get(self, request: Request) -> Response:
        subscriptions = WebhookSubscription.objects.filter(client=_client(request))
        return Response(WebhookSubscriptionSerializer(subscriptions, many=True).data)

    @extend_schema(
        request=InputSerializer,
        responses={
            201: WebhookSubscriptionCreatedSerializer,
            422: OpenApiResponse(description="Unknown event types."),
        },
    )
    def post(self, request: Request) -> Response:
        client = _client(request)
        data = self.InputSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        subscription = services.create_webhook_subscription(client=client, **data.validated_data)
        return Response(
            WebhookSubscriptionCreatedSerializer(subscription).data, status=status.HTTP_201_CREATED
        )


class WebhookSubscriptionDetailApi(APIView):
    """GET: one subscription. DELETE: unsubscribe (its delivery log goes too)."""

    @extend_schema(responses=WebhookSubscriptionSerializer)
    def get(self, request: Request, pk: int) -> Response:
        return Response(WebhookSubscriptionSerializer(_subscription(request, pk)).data)

    @extend_schema(responses={204: None})
    def delete(self, request: Request, pk: int) -> Response:
        services.delete_webhook_subscription(subscription=_subscription(request, pk))
        return Response(status=status.HTTP_204_NO_CONTENT)


class WebhookSubscriptionPingApi(APIView):
    """Queue a `ping` event to this subscription, to test the endpoint and the signature."""

    @extend_schema(request=None, responses={202: None})
    def post(self, request: Request, pk: int) -> Response:
        services.ping_webhook_subscription(subscription=_subscription(request, pk))
        return Response(status=status.HTTP_202_ACCEPTED)
