"""Settings for the test run: the project settings on the services tests.services chose."""

from tests.services import choose

SERVICES = choose()

from fleet.settings import *  # noqa: E402,F403

SECRET_KEY = "test-secret-key"  # noqa: S105
PASSWORD_HASHERS = ["django.contrib.auth.hashers.MD5PasswordHasher"]
CELERY_TASK_ALWAYS_EAGER = True  # tests that need a real worker start one as a process
WHITENOISE_USE_FINDERS = True  # serve static from the apps in tests, no collectstatic needed
WHITENOISE_AUTOREFRESH = True
