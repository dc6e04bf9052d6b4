from django.urls import path
from rest_framework.routers import SimpleRouter

from maps.api.views import LifImportApi, MapViewSet, SiteViewSet, StationViewSet

router = SimpleRouter()
router.register("maps", MapViewSet)
router.register("sites", SiteViewSet)
router.register("stations", StationViewSet)
urlpatterns = [
    path("lif/import/", LifImportApi.as_view(), name="lif-import"),
    *router.urls,
]
