from django.urls import path

from battery import views

app_name = "battery"
urlpatterns = [
    path("", views.overview, name="overview"),
    path("vehicles/<int:pk>/", views.vehicle_detail, name="vehicle"),
]
