from django.urls import path
from rest_framework.routers import SimpleRouter

from maps.api.releases import MapReleaseViewSet
from maps.api.views import LifImportApi, MapViewSet, SiteViewSet, StationViewSet, ZoneViewSet

router = SimpleRouter()
router.register("maps", MapViewSet)
router.register("map-releases", MapReleaseViewSet)
router.register("sites", SiteViewSet)
router.register("stations", StationViewSet)
router.register("zones", ZoneViewSet)
urlpatterns = [
    path("lif/import/", LifImportApi.as_view(), name="lif-import"),
    *router.urls,
]
