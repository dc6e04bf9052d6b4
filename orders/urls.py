"""URLs of the staff orders pages."""

from django.urls import path

from orders import views

app_name = "orders"
urlpatterns = [
    path("", views.order_list, name="list"),
    path("new/", views.order_create, name="create"),
    path("<int:pk>/cancel/", views.order_cancel, name="cancel"),
    path("<int:pk>/priority/", views.order_priority, name="priority"),
    path("<int:pk>/reassign/", views.order_reassign, name="reassign"),
    path("recurring/", views.recurring_list, name="recurring"),
]
