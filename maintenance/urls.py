from django.urls import path

from maintenance import views

app_name = "maintenance"
urlpatterns = [
    path("", views.overview, name="overview"),
    path("vehicles/<int:pk>/", views.vehicle_detail, name="vehicle"),
    path("vehicles/<int:pk>/service/", views.vehicle_service, name="vehicle_service"),
    path("work-orders/<int:pk>/", views.work_order_detail, name="work_order"),
]
