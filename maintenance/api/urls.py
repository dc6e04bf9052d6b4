from django.urls import path

from maintenance.api import views

urlpatterns = [
    path("maintenance/plans/", views.ServicePlanListApi.as_view(), name="maintenance-plans"),
    path(
        "maintenance/work-orders/",
        views.WorkOrderListApi.as_view(),
        name="maintenance-work-orders",
    ),
    path(
        "maintenance/vehicles/",
        views.VehicleCountersListApi.as_view(),
        name="maintenance-vehicles",
    ),
    path(
        "maintenance/vehicles/<id:pk>/history/",
        views.ServiceHistoryApi.as_view(),
        name="maintenance-history",
    ),
    path(
        "maintenance/vehicles/<id:pk>/errors/",
        views.VehicleErrorsApi.as_view(),
        name="maintenance-errors",
    ),
]
