"""Settings from the environment (django-environ).

Unset service URLs fall back to embedded defaults so that `make demo` runs on a machine with only
Python: SQLite instead of PostgreSQL, an in-memory channel layer and eager Celery instead of Redis,
and the embedded amqtt broker instead of Mosquitto. Setting DATABASE_URL, REDIS_URL and MQTT_URL
switches to the production topology (see the Procfile).
"""

from pathlib import Path

import django_stubs_ext
import environ

django_stubs_ext.monkeypatch()  # ModelAdmin[Model] and friends at run time, for typed code

BASE_DIR = Path(__file__).resolve().parent.parent

env = environ.Env()
env.read_env(BASE_DIR / ".env", overwrite=False)

DEBUG = env.bool("DEBUG", default=False)
SECRET_KEY = env.str("SECRET_KEY", default="insecure-development-key-set-SECRET_KEY-in-production")
ALLOWED_HOSTS = env.list("ALLOWED_HOSTS", default=["localhost", "127.0.0.1", "[::1]", "testserver"])
CSRF_TRUSTED_ORIGINS = env.list("CSRF_TRUSTED_ORIGINS", default=[])

INSTALLED_APPS = [
    "daphne",
    "django.contrib.admin",
    "django.contrib.auth",
    "django.contrib.contenttypes",
    "django.contrib.sessions",
    "django.contrib.messages",
    "whitenoise.runserver_nostatic",
    "django.contrib.staticfiles",
    "rest_framework",
    "drf_spectacular",
    "drf_spectacular_sidecar",  # Swagger UI and Redoc served by the app (no CDN)
    "channels",
    "fleet",
    "maps",
    "robots",
    "battery",
    "maintenance",
    "inventory",
    "alerts",
    "orders",
    "reports",
    "control",
]

MIDDLEWARE = [
    "django.middleware.security.SecurityMiddleware",
    "whitenoise.middleware.WhiteNoiseMiddleware",
    "django.contrib.sessions.middleware.SessionMiddleware",
    "django.middleware.common.CommonMiddleware",
    "django.middleware.csrf.CsrfViewMiddleware",
    "django.contrib.auth.middleware.AuthenticationMiddleware",
    "django.contrib.messages.middleware.MessageMiddleware",
    "django.middleware.clickjacking.XFrameOptionsMiddleware",
]

ROOT_URLCONF = "fleet.urls"
ASGI_APPLICATION = "fleet.asgi.application"
WSGI_APPLICATION = None

TEMPLATES = [
    {
        "BACKEND": "django.template.backends.django.DjangoTemplates",
        "DIRS": [BASE_DIR / "templates"],
        "APP_DIRS": True,
        "OPTIONS": {
            "context_processors": [
                "django.template.context_processors.request",
                "django.contrib.auth.context_processors.auth",
                "django.contrib.messages.context_processors.messages",
            ],
        },
    },
]

# Database: PostgreSQL in production, SQLite when DATABASE_URL is unset.
DATABASES = {"default": env.db("DATABASE_URL", default=f"sqlite:///{BASE_DIR / 'db.sqlite3'}")}
if DATABASES["default"]["ENGINE"] == "django.db.backends.sqlite3":
    # Several threads write in the demo (control's flusher, web, eager dispatch): wait for the
    # lock instead of failing, and take it at BEGIN so that read-then-write never deadlocks.
    DATABASES["default"]["OPTIONS"] = {
        "timeout": 30,
        "transaction_mode": "IMMEDIATE",
        "init_command": "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL;",
    }
else:
    DATABASES["default"].setdefault("CONN_MAX_AGE", 60)
    DATABASES["default"].setdefault("CONN_HEALTH_CHECKS", True)
DEFAULT_AUTO_FIELD = "django.db.models.BigAutoField"

# Redis: Celery broker, channel layer and control's command queue. Unset = embedded stand-ins.
REDIS_URL = env.str("REDIS_URL", default="")
if REDIS_URL:
    CHANNEL_LAYERS = {
        "default": {
            "BACKEND": "channels_redis.core.RedisChannelLayer",
            # channels_redis waits 5 s per receive; redis-py 8 would time the read out at 5 s
            # and drop idle websockets (django/channels_redis#422), so no socket timeout.
            "CONFIG": {
                "hosts": [{"address": REDIS_URL, "socket_timeout": None}],
                "capacity": 1000,
                "expiry": 10,
            },
        }
    }
else:
    CHANNEL_LAYERS = {"default": {"BACKEND": "channels.layers.InMemoryChannelLayer"}}

CELERY_BROKER_URL = REDIS_URL or "memory://"
CELERY_RESULT_BACKEND = None
CELERY_TASK_ALWAYS_EAGER = env.bool("CELERY_TASK_ALWAYS_EAGER", default=not REDIS_URL)
CELERY_TASK_EAGER_PROPAGATES = True
CELERY_TASK_ACKS_LATE = True
CELERY_TASK_REJECT_ON_WORKER_LOST = True
CELERY_WORKER_PREFETCH_MULTIPLIER = 1
CELERY_BROKER_TRANSPORT_OPTIONS = {"visibility_timeout": 300}
CELERY_BEAT_SCHEDULE = {
    "dispatch-cycle": {"task": "orders.tasks.dispatch_pending_orders", "schedule": 5.0},
}

# MQTT: Mosquitto in production; the embedded amqtt broker when MQTT_URL is unset.
MQTT_EMBEDDED = not env.str("MQTT_URL", default="")
MQTT_EMBEDDED_PORT = env.int("MQTT_EMBEDDED_PORT", default=11883)
MQTT_URL = env.str("MQTT_URL", default=f"mqtt://127.0.0.1:{MQTT_EMBEDDED_PORT}")
VDA5050_INTERFACE = env.str("VDA5050_INTERFACE", default="uagv")

# The master control process (`manage.py run_control`).
FLEET_CONTROL = {
    "FLUSH_INTERVAL": env.float("FLEET_FLUSH_INTERVAL", default=1.0),
    "BROADCAST_INTERVAL": env.float("FLEET_BROADCAST_INTERVAL", default=0.2),
    "SYNC_INTERVAL": env.float("FLEET_SYNC_INTERVAL", default=1.0),
    # How many route nodes ahead of a vehicle are released (its VDA 5050 base); the rest is
    # sent as horizon and released with order updates as the vehicle advances. 0 = all at once.
    "BASE_AHEAD": env.int("FLEET_BASE_AHEAD", default=3),
}

AUTH_PASSWORD_VALIDATORS = [
    {"NAME": "django.contrib.auth.password_validation.UserAttributeSimilarityValidator"},
    {"NAME": "django.contrib.auth.password_validation.MinimumLengthValidator"},
    {"NAME": "django.contrib.auth.password_validation.CommonPasswordValidator"},
    {"NAME": "django.contrib.auth.password_validation.NumericPasswordValidator"},
]
LOGIN_URL = "admin:login"

REST_FRAMEWORK = {
    "DEFAULT_AUTHENTICATION_CLASSES": [
        # Integration clients send `Authorization: Bearer <token>`; browsers use the session.
        "orders.api.authentication.ClientTokenAuthentication",
        "rest_framework.authentication.SessionAuthentication",
        "rest_framework.authentication.BasicAuthentication",
    ],
    "DEFAULT_PERMISSION_CLASSES": ["rest_framework.permissions.IsAuthenticated"],
    "EXCEPTION_HANDLER": "fleet.exceptions.api_exception_handler",
    "DEFAULT_PAGINATION_CLASS": "orders.api.pagination.BoundedLimitOffsetPagination",
    "PAGE_SIZE": 50,
    "DEFAULT_SCHEMA_CLASS": "drf_spectacular.openapi.AutoSchema",
}

SPECTACULAR_SETTINGS = {
    "TITLE": "Open Fleet API",
    "DESCRIPTION": (
        "Transport orders, vehicles and webhooks for ERP/WMS integrations. Authenticate with "
        "`Authorization: Bearer <token>` (an integration client's token, issued in the admin). "
        "Errors: 400 bad input (per field), 401 no or bad token, 404 unknown id, 409 not "
        "allowed in the current state, 422 cannot be carried out; `detail` says why."
    ),
    "VERSION": "1.0.0",
    "SCHEMA_PATH_PREFIX": "/api/v1",
    "SERVE_INCLUDE_SCHEMA": False,
    "SERVE_PERMISSIONS": ["rest_framework.permissions.IsAuthenticated"],
    "COMPONENT_SPLIT_REQUEST": True,
    "PATH_CONVERTER_OVERRIDE": {
        "id": {"type": "integer", "minimum": 1, "maximum": 999999999999999999}
    },
    "POSTPROCESSING_HOOKS": [
        "drf_spectacular.hooks.postprocess_schema_enums",
        "orders.api.schema.add_error_responses",
    ],
    "SWAGGER_UI_DIST": "SIDECAR",
    "SWAGGER_UI_FAVICON_HREF": "SIDECAR",
    "REDOC_DIST": "SIDECAR",
}

LANGUAGE_CODE = "en-us"
TIME_ZONE = env.str("TIME_ZONE", default="UTC")
USE_I18N = True
USE_TZ = True

STATIC_URL = "static/"
STATIC_ROOT = BASE_DIR / "staticfiles"
STATICFILES_DIRS = [BASE_DIR / "static"]

LOGGING = {
    "version": 1,
    "disable_existing_loggers": False,
    "formatters": {"plain": {"format": "%(asctime)s %(levelname)s %(name)s: %(message)s"}},
    "handlers": {"console": {"class": "logging.StreamHandler", "formatter": "plain"}},
    "root": {"handlers": ["console"], "level": env.str("LOG_LEVEL", default="INFO")},
    "loggers": {
        "django.channels.server": {"level": "WARNING"},
        "celery.app.trace": {"level": "WARNING"},  # one line per task drowns the rest
    },
}
