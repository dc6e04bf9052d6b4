"""URLs of the layout pages: the list of maps and the layout editor."""

from django.urls import path

from maps import views

app_name = "maps"
urlpatterns = [
    path("", views.layout_list, name="list"),
    path("<int:pk>/edit/", views.layout_editor, name="edit"),
    path("<int:pk>/check/", views.layout_check, name="check"),
    path("<int:pk>/save/", views.layout_save, name="save"),
    path("<int:pk>/floor-plan/", views.floor_plan, name="floor-plan"),
    path("releases/<str:token>/<str:name>", views.release_file, name="release-file"),
]
