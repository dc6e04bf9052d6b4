from django.urls import path

from battery.api import views

urlpatterns = [
    path("battery/vehicles/", views.VehicleEnergyListApi.as_view(), name="battery-vehicles"),
    path(
        "battery/vehicles/<id:pk>/history/",
        views.BatteryHistoryApi.as_view(),
        name="battery-history",
    ),
    path("battery/chargers/", views.ChargerListApi.as_view(), name="battery-chargers"),
    path("battery/sessions/", views.ChargeSessionListApi.as_view(), name="battery-sessions"),
]
