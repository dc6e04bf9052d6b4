"""Settings for `bench.live_map`: the project's, with static files served from the source
folders (no collectstatic into the shared tree for a throw-away server)."""

from fleet.settings import *  # noqa: F403

WHITENOISE_USE_FINDERS = True
