from django.urls import path

from orders.api import vehicle_views, views, webhook_views

urlpatterns = [
    path("orders/", views.TransportOrderListCreateApi.as_view(), name="order-list"),
    path("orders/<id:pk>/", views.TransportOrderDetailApi.as_view(), name="order-detail"),
    path("orders/<id:pk>/cancel/", views.TransportOrderCancelApi.as_view(), name="order-cancel"),
    path(
        "orders/<id:pk>/priority/",
        views.TransportOrderPriorityApi.as_view(),
        name="order-priority",
    ),
    path("vehicles/<id:pk>/pause/", vehicle_views.VehiclePauseApi.as_view(), name="vehicle-pause"),
    path(
        "vehicles/<id:pk>/commands/",
        vehicle_views.VehicleCommandListApi.as_view(),
        name="vehicle-commands",
    ),
    path(
        "vehicles/<id:pk>/resume/", vehicle_views.VehicleResumeApi.as_view(), name="vehicle-resume"
    ),
    path(
        "vehicles/<id:pk>/charge/", vehicle_views.VehicleChargeApi.as_view(), name="vehicle-charge"
    ),
    path("vehicles/<id:pk>/park/", vehicle_views.VehicleParkApi.as_view(), name="vehicle-park"),
    path(
        "vehicles/<id:pk>/instant-actions/",
        vehicle_views.VehicleInstantActionApi.as_view(),
        name="vehicle-instant-actions",
    ),
    path(
        "webhooks/",
        webhook_views.WebhookSubscriptionListCreateApi.as_view(),
        name="webhook-list",
    ),
    path(
        "webhooks/<id:pk>/",
        webhook_views.WebhookSubscriptionDetailApi.as_view(),
        name="webhook-detail",
    ),
    path(
        "webhooks/<id:pk>/ping/",
        webhook_views.WebhookSubscriptionPingApi.as_view(),
        name="webhook-ping",
    ),
]
