"""URLs of the staff orders pages."""

from django.urls import path

from orders import board, views

app_name = "orders"
urlpatterns = [
    path("", board.orders_page, name="list"),  # the board; the list with ?view=list
    path("new/", views.order_create, name="create"),
    path("<int:pk>/cancel/", views.order_cancel, name="cancel"),
    path("<int:pk>/priority/", views.order_priority, name="priority"),
    path("<int:pk>/reassign/", views.order_reassign, name="reassign"),
    path("recurring/", views.recurring_list, name="recurring"),
]
