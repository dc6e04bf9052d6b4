"""URLs of the inventory pages."""

from django.urls import re_path

from inventory import views

app_name = "inventory"

urlpatterns = [
    re_path(r"^$", views.stock, name="stock"),
    re_path(r"^(?P<kind>locations|stock)\.csv$", views.export, name="export"),
    re_path(r"^(?P<kind>locations|stock)/import/$", views.import_, name="import"),
]
