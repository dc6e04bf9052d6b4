from rest_framework.routers import SimpleRouter

from robots.api.views import VehicleViewSet

router = SimpleRouter()
router.register("vehicles", VehicleViewSet)
urlpatterns = router.urls
