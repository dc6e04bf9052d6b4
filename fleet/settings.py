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
# Secrets come from the environment or, for container secrets, from a file (SECRET_KEY_FILE).
SECRET_KEY = (
    Path(env.str("SECRET_KEY_FILE")).read_text().strip()
    if env.str("SECRET_KEY_FILE", default="")
    else env.str("SECRET_KEY", default="django-insecure-set-SECRET_KEY-in-production")
)
ALLOWED_HOSTS = env.list("ALLOWED_HOSTS", default=["localhost", "127.0.0.1", "[::1]", "testserver"])
CSRF_TRUSTED_ORIGINS = env.list("CSRF_TRUSTED_ORIGINS", default=[])

# Served over HTTPS (production): secure cookies, HSTS and a redirect to HTTPS. Off by default
# because the demo serves plain HTTP on localhost, where secure cookies would break the login.
FLEET_HTTPS = env.bool("FLEET_HTTPS", default=False)
SECURE_SSL_REDIRECT = env.bool("SECURE_SSL_REDIRECT", default=FLEET_HTTPS)
SESSION_COOKIE_SECURE = CSRF_COOKIE_SECURE = FLEET_HTTPS
SECURE_HSTS_SECONDS = env.int("SECURE_HSTS_SECONDS", default=31_536_000 if FLEET_HTTPS else 0)
SECURE_HSTS_INCLUDE_SUBDOMAINS = env.bool("SECURE_HSTS_INCLUDE_SUBDOMAINS", default=FLEET_HTTPS)
SECURE_HSTS_PRELOAD = env.bool("SECURE_HSTS_PRELOAD", default=FLEET_HTTPS)
if env.bool("FLEET_BEHIND_PROXY", default=False):  # TLS ends at a reverse proxy that says so
    SECURE_PROXY_SSL_HEADER = ("HTTP_X_FORWARDED_PROTO", "https")
SESSION_COOKIE_AGE = env.int("SESSION_COOKIE_AGE", default=12 * 3600)  # one shift
# Request bodies beyond this are refused with 400 before parsing (LIF files of 5,000+ nodes fit).
DATA_UPLOAD_MAX_MEMORY_SIZE = env.int("MAX_REQUEST_BYTES", default=32 * 1024 * 1024)

INSTALLED_APPS = [
    "daphne",
    "fleet.admin_site.FleetAdminConfig",  # django.contrib.admin, entered by role (fleet.roles)
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
    "axes",  # login throttling: locks a user name + address out after repeated failures
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
    "fleet.middleware.DatabaseUnavailableMiddleware",  # database down: 503 + Retry-After
    "whitenoise.middleware.WhiteNoiseMiddleware",
    "django.contrib.sessions.middleware.SessionMiddleware",
    "django.middleware.common.CommonMiddleware",
    "django.middleware.csrf.CsrfViewMiddleware",
    "django.contrib.auth.middleware.AuthenticationMiddleware",
    "fleet.audit.AuditMiddleware",  # services record who did what, from where
    "django.contrib.messages.middleware.MessageMiddleware",
    "django.middleware.clickjacking.XFrameOptionsMiddleware",
    "axes.middleware.AxesMiddleware",  # last, as django-axes asks
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
    # 0 (close at the end of each request) by default: under ASGI daphne runs views in a thread
    # pool, and persistent connections pile up per thread until PostgreSQL refuses new clients
    # (the idempotency fault row hit "too many clients" with 60). Long-running processes
    # (control, workers) reconnect cheaply once per flush or task.
    DATABASES["default"].setdefault("CONN_MAX_AGE", env.int("DB_CONN_MAX_AGE", default=0))
    DATABASES["default"].setdefault("CONN_HEALTH_CHECKS", True)
DEFAULT_AUTO_FIELD = "django.db.models.BigAutoField"

# Redis: Celery broker, channel layer and control's command queue. Unset = embedded stand-ins.
REDIS_URL = env.str("REDIS_URL", default="")
if REDIS_URL:
    from redis.asyncio.retry import Retry
    from redis.backoff import ExponentialBackoff
    from redis.exceptions import ConnectionError as RedisConnectionError

    CHANNEL_LAYERS = {
        "default": {
            "BACKEND": "channels_redis.core.RedisChannelLayer",
            # channels_redis waits 5 s per receive; redis-py 8 would time the read out at 5 s
            # and drop idle websockets (django/channels_redis#422), so no socket timeout.
            # After a Redis restart a pooled connection can be dead: retry a command on a new
            # one instead of failing the websocket's connect (bench/faults redis row).
            "CONFIG": {
                "hosts": [
                    {
                        "address": REDIS_URL,
                        "socket_timeout": None,
                        "retry": Retry(ExponentialBackoff(cap=0.5, base=0.05), 3),
                        "retry_on_error": [RedisConnectionError],
                    }
                ],
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
    "charging-cycle": {"task": "battery.tasks.plan_charging", "schedule": 5.0},
    "service-plans": {"task": "maintenance.tasks.check_service_plans", "schedule": 60.0},
    "reports-roll-up": {"task": "reports.tasks.roll_up_orders", "schedule": 60.0},
    "reports-sample": {"task": "reports.tasks.sample_vehicles", "schedule": 15.0},
    "reports-traffic-waits": {"task": "reports.tasks.roll_up_traffic_waits", "schedule": 60.0},
    "alerts-escalate": {"task": "alerts.escalate", "schedule": 60.0},
}

# Alerts (issue 8): escalation mail goes through Django's email backend (console when no SMTP
# host is configured, so a closed plant network never blocks on mail).
EMAIL_BACKEND = env.str(
    "EMAIL_BACKEND",
    default="django.core.mail.backends.smtp.EmailBackend"
    if env.str("EMAIL_HOST", default="")
    else "django.core.mail.backends.console.EmailBackend",
)
EMAIL_HOST = env.str("EMAIL_HOST", default="localhost")
EMAIL_PORT = env.int("EMAIL_PORT", default=25)
DEFAULT_FROM_EMAIL = env.str("DEFAULT_FROM_EMAIL", default="fleet@localhost")
ALERTS_LOW_BATTERY_PERCENT = env.float("ALERTS_LOW_BATTERY_PERCENT", default=20.0)
ALERTS_NO_PROGRESS_SECONDS = env.float("ALERTS_NO_PROGRESS_SECONDS", default=120.0)
# Shifts for the reports: (name, start hour in TIME_ZONE); each lasts until the next starts.
REPORT_SHIFTS = [("early", 6), ("late", 14), ("night", 22)]

# MQTT: Mosquitto in production; the embedded amqtt broker when MQTT_URL is unset.
MQTT_EMBEDDED = not env.str("MQTT_URL", default="")
MQTT_EMBEDDED_PORT = env.int("MQTT_EMBEDDED_PORT", default=11883)
MQTT_URL = env.str("MQTT_URL", default=f"mqtt://127.0.0.1:{MQTT_EMBEDDED_PORT}")
VDA5050_INTERFACE = env.str("VDA5050_INTERFACE", default="uagv")

# The master control process (`manage.py run_control`).
FLEET_CONTROL = {
    "FLUSH_INTERVAL": env.float("FLEET_FLUSH_INTERVAL", default=1.0),
    # A vehicle whose snapshot changed only in motion (position, last node, battery charge,
    # last seen) is written at most this often; any other change goes with the next flush.
    # The live page gets positions over websockets; the database rows serve lists, dispatch
    # and counters (1,000 driving vehicles: 1,150 -> 360 rows a second, docs/LOAD.md).
    "MOTION_FLUSH_INTERVAL": env.float("FLEET_MOTION_FLUSH_INTERVAL", default=5.0),
    "BROADCAST_INTERVAL": env.float("FLEET_BROADCAST_INTERVAL", default=0.2),
    # Browser rows control builds per second at most: a large fleet's live page is updated less
    # often than every BROADCAST_INTERVAL (1,000 moving vehicles: about once a second, the rate
    # of their visualization messages) instead of rebuilding 2,000+ rows a second.
    "BROADCAST_ROWS_PER_S": env.float("FLEET_BROADCAST_ROWS_PER_S", default=1000.0),
    "SYNC_INTERVAL": env.float("FLEET_SYNC_INTERVAL", default=1.0),
    # Seconds control's MQTT client waits at least between two socket reads: under load a
    # read then brings a dozen messages instead of one or two (fewer wake-ups and system
    # calls), for at most this much added latency (docs/LOAD.md, ninth round). 0 = off.
    "MQTT_READ_PAUSE": env.float("FLEET_MQTT_READ_PAUSE", default=0.004),
    # Seconds between full reads of the active orders from the database (the syncs between
    # them work on the last read; a command, e.g. a cancellation, makes the next sync read).
    "ORDER_READ_INTERVAL": env.float("FLEET_ORDER_READ_INTERVAL", default=3.0),
    # Alerts, inventory, battery and maintenance counters evaluate the flushed snapshots at
    # most this often (seconds; the newest snapshot per vehicle counts).
    "OBSERVE_INTERVAL": env.float("FLEET_OBSERVE_INTERVAL", default=2.0),
    # How many route nodes ahead of a vehicle are released (its VDA 5050 base); the rest is
    # sent as horizon and released with order updates as the vehicle advances. 0 = all at once.
    "BASE_AHEAD": env.int("FLEET_BASE_AHEAD", default=3),
    # How many unreleased nodes after the base an order carries (its horizon); 0 = the rest of
    # the route. Vehicles repeat the horizon in every state, so a whole-route horizon makes
    # every state message as long as the route (docs/LOAD.md, eighth round).
    "HORIZON_NODES": env.int("FLEET_HORIZON_NODES", default=10),
    # Traffic management (control/traffic_link.py) decides each base; off = BASE_AHEAD only,
    # enough for a single-vehicle site.
    "TRAFFIC": env.bool("FLEET_TRAFFIC", default=True),
    # Idle vehicles that keep an order from being planned are sent to a park station.
    "TRAFFIC_PARK_IDLE": env.bool("FLEET_TRAFFIC_PARK_IDLE", default=True),
    # Seconds an idle vehicle without an order may stand off a park station (on a drop
    # station, in an aisle) before it is sent to the nearest free one; 0 = off (only when in
    # an order's way, above). With a steady order stream the next order then finds its
    # station free instead of parking the vehicle first (docs/LOAD.md, tenth round).
    "TRAFFIC_PARK_AFTER": env.float("FLEET_TRAFFIC_PARK_AFTER", default=0.0),
    # Seconds of silence before control sends a vehicle one stateRequest; no state within 5 s
    # = UNREACHABLE (a frozen vehicle declaring a 30 s state interval: ~16 s, not 35). 0 = off.
    "LIVENESS_PROBE_AFTER": env.float("FLEET_LIVENESS_PROBE_AFTER", default=10.0),
}
# Where control's flush hands finished traffic waits (vehicle held at its decision point): the
# reports app records them. Wired here because control and reports are independent siblings.
FLEET_TRAFFIC_WAIT_RECORDER = "reports.waits.record_traffic_waits"
# control's /health and /ready (control/health.py; 0 = off). Two controls on one host (a
# standby pair) need two ports.
CONTROL_HEALTH_PORT = env.int("CONTROL_HEALTH_PORT", default=8081)
# control is one long-lived process with two database threads (flush, floor observer): it keeps
# its connections (seconds) instead of opening one per flush, as DB_CONN_MAX_AGE=0 does.
CONTROL_DB_CONN_MAX_AGE = env.int("CONTROL_DB_CONN_MAX_AGE", default=300)
# Celery pool processes run one task at a time: each keeps its connection (fleet/celery.py).
WORKER_DB_CONN_MAX_AGE = env.int("WORKER_DB_CONN_MAX_AGE", default=300)
# For the load benchmark (bench/load): a file where control writes, per order update it
# publishes while handling a state message, which state that was (control/metrics.py CauseLog).
CONTROL_CAUSE_LOG = env.str("CONTROL_CAUSE_LOG", default="")
# Allocations between collections of control's youngest generation (Python's default is 700).
CONTROL_GC_THRESHOLD = env.int("CONTROL_GC_THRESHOLD", default=50_000)
# Seconds between the GIL hand-overs Python forces in control (its default is 0.005): shorter
# lets the paho thread take messages off the socket sooner while another thread computes,
# longer costs fewer thread switches (docs/LOAD.md, third and thirteenth rounds).
CONTROL_SWITCH_INTERVAL = env.float("CONTROL_SWITCH_INTERVAL", default=0.001)
# Leadership of a standby pair (control/leader.py LeaseTimes, seconds): renew the lease every
# RENEW_EVERY; publish only within LEASE of the last renewal; the database ends a silent leader's
# session after SERVER_TIMEOUT; a new leader waits GUARD; a standby polls every RETRY_EVERY; a
# process that stepped down waits REJOIN_AFTER. Need RENEW_EVERY < LEASE < SERVER_TIMEOUT, GUARD.
CONTROL_LEASE = {
    "RENEW_EVERY": env.float("CONTROL_RENEW_SECONDS", default=0.5),
    "LEASE": env.float("CONTROL_LEASE_SECONDS", default=5.0),
    "SERVER_TIMEOUT": env.float("CONTROL_SERVER_TIMEOUT_SECONDS", default=6.0),
    "GUARD": env.float("CONTROL_GUARD_SECONDS", default=5.5),
    "RETRY_EVERY": env.float("CONTROL_RETRY_SECONDS", default=0.5),
    "REJOIN_AFTER": env.float("CONTROL_REJOIN_SECONDS", default=2.0),
}
# GET /metrics (Prometheus, control/prometheus.py): anonymous scrapes from these networks only,
# others need `Authorization: Bearer <METRICS_TOKEN>` (unset: no token is accepted).
METRICS_ALLOWED_CIDRS = env.list("METRICS_ALLOWED_CIDRS", default=["127.0.0.1/32"])
METRICS_TOKEN = env.str("METRICS_TOKEN", default="")

AUTH_PASSWORD_VALIDATORS = [
    {"NAME": "django.contrib.auth.password_validation.UserAttributeSimilarityValidator"},
    {"NAME": "django.contrib.auth.password_validation.MinimumLengthValidator"},
    {"NAME": "django.contrib.auth.password_validation.CommonPasswordValidator"},
    {"NAME": "django.contrib.auth.password_validation.NumericPasswordValidator"},
]
LOGIN_URL = "login"
LOGIN_REDIRECT_URL = "/"
LOGOUT_REDIRECT_URL = "login"
AUTHENTICATION_BACKENDS = [
    "axes.backends.AxesStandaloneBackend",  # refuses locked-out logins before checking them
    "django.contrib.auth.backends.ModelBackend",
]
# After AXES_FAILURE_LIMIT failed logins for one user name from one address, that pair is locked
# out for AXES_COOLOFF_MINUTES (HTTP 429); a successful login resets the count.
AXES_FAILURE_LIMIT = env.int("AXES_FAILURE_LIMIT", default=5)
AXES_COOLOFF_TIME = env.float("AXES_COOLOFF_MINUTES", default=15) / 60
AXES_LOCKOUT_PARAMETERS = [["username", "ip_address"]]
AXES_RESET_ON_SUCCESS = True
AXES_HTTP_RESPONSE_CODE = 429
if env.bool("FLEET_BEHIND_PROXY", default=False):
    AXES_IPWARE_PROXY_COUNT = 1
    AXES_IPWARE_META_PRECEDENCE_ORDER = ["HTTP_X_FORWARDED_FOR", "REMOTE_ADDR"]

REST_FRAMEWORK = {
    "DEFAULT_AUTHENTICATION_CLASSES": [
        # Integration clients send `Authorization: Bearer <token>`; browsers use the session.
        "orders.api.authentication.ClientTokenAuthentication",
        "rest_framework.authentication.SessionAuthentication",
        "rest_framework.authentication.BasicAuthentication",
    ],
    # Tokens need the endpoint's scope, users their role's permission (fleet/api_access.py).
    "DEFAULT_PERMISSION_CLASSES": ["fleet.api_access.ScopedAccess"],
    "EXCEPTION_HANDLER": "fleet.exceptions.api_exception_handler",
    "DEFAULT_PAGINATION_CLASS": "orders.api.pagination.BoundedLimitOffsetPagination",
    "PAGE_SIZE": 50,
    "DEFAULT_SCHEMA_CLASS": "drf_spectacular.openapi.AutoSchema",
    # Per integration client (its user) and per address for anonymous calls: 429 beyond.
    "DEFAULT_THROTTLE_CLASSES": [
        "rest_framework.throttling.AnonRateThrottle",
        "rest_framework.throttling.UserRateThrottle",
    ],
    "DEFAULT_THROTTLE_RATES": {
        "anon": env.str("API_ANON_RATE", default="120/min"),
        "user": env.str("API_CLIENT_RATE", default="6000/min"),
    },
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
# Uploaded files (floor plans, work-order attachments). Served only to logged-in staff by
# fleet.media, never as public static files; back this directory up with the database.
MEDIA_ROOT = env.path("MEDIA_ROOT", default=BASE_DIR / "media")
MEDIA_URL = "/media/"

# LOG_FORMAT=json: one JSON object per line for a log collector (fleet/logging.py); plain otherwise.
LOG_FORMAT = env.str("LOG_FORMAT", default="plain")
LOGGING = {
    "version": 1,
    "disable_existing_loggers": False,
    "formatters": {
        "plain": {"format": "%(asctime)s %(levelname)s %(name)s: %(message)s"},
        "json": {"()": "fleet.logging.JsonFormatter"},
    },
    "handlers": {
        "console": {
            "class": "logging.StreamHandler",
            "formatter": "json" if LOG_FORMAT == "json" else "plain",
        }
    },
    "root": {"handlers": ["console"], "level": env.str("LOG_LEVEL", default="INFO")},
    "loggers": {
        "django.channels.server": {"level": "WARNING"},
        "celery.app.trace": {"level": "WARNING"},  # one line per task drowns the rest
        "axes": {"level": "WARNING"},  # one line per start and per login otherwise
    },
}
