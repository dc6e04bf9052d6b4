from rest_framework.routers import SimpleRouter

from maps.api.views import MapViewSet, StationViewSet

router = SimpleRouter()
router.register("maps", MapViewSet)
router.register("stations", StationViewSet)
urlpatterns = router.urls
