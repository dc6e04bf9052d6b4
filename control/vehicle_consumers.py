"""The vehicle page's websocket: one vehicle's raw VDA 5050 messages, while the page is open.

The consumer joins the vehicle's group and asks `control` to watch the vehicle (a
`vehicle.watch` command); the page renews the watch every few seconds, and `control` lets a
watch lapse when no page renews it, so it streams only what someone looks at.
"""

import time
from typing import Any

from asgiref.sync import sync_to_async
from channels.db import database_sync_to_async
from channels.generic.websocket import AsyncJsonWebsocketConsumer

from control.message_log import WATCH_SECONDS
from fleet import roles
from fleet.control_queue import send_command
from fleet.realtime import remember_web_loop, vehicle_group

NOT_LOGGED_IN = 4401
NOT_PERMITTED = 4403
MIN_RENEWAL_SECONDS = 5.0  # renewals more often than this are ignored (a page sends every 10 s)


class VehicleConsumer(AsyncJsonWebsocketConsumer):  # type: ignore[misc]
    """Streams `vehicle.messages` of one vehicle to a user who may view operations."""

    vehicle_pk: int | None = None
    _renewed_at: float = float("-inf")

    async def connect(self) -> None:
        user = self.scope.get("user")
        if user is None or not user.is_authenticated:
            await self.close(code=NOT_LOGGED_IN)
            return
        if not await database_sync_to_async(user.has_perm)(roles.VIEW_OPERATIONS):
            await self.close(code=NOT_PERMITTED)
            return
        self.vehicle_pk = int(self.scope["url_route"]["kwargs"]["pk"])
        remember_web_loop()
        await self.channel_layer.group_add(vehicle_group(self.vehicle_pk), self.channel_name)
        await self.accept()
        await self._send_watch(full=True)  # control resends the latest of every topic

    async def disconnect(self, code: int) -> None:
        if self.vehicle_pk is not None:
            await self.channel_layer.group_discard(
                vehicle_group(self.vehicle_pk), self.channel_name
            )

    async def receive_json(self, content: Any, **kwargs: Any) -> None:
        """A renewal from the page (`full` while it has nothing yet, e.g. the vehicle had not
        connected since control started); renewals closer together than 5 s are ignored."""
        if not isinstance(content, dict) or content.get("type") != "watch":
            return
        now = time.monotonic()
        if now - self._renewed_at < MIN_RENEWAL_SECONDS:
            return
        await self._send_watch(full=bool(content.get("full")))

    async def fleet_event(self, message: dict[str, Any]) -> None:
        await self.send_json({"event": message["event"], "payload": message["payload"]})

    async def _send_watch(self, *, full: bool) -> None:
        self._renewed_at = time.monotonic()
        await sync_to_async(send_command)(
            "vehicle.watch", vehicle=self.vehicle_pk, seconds=WATCH_SECONDS, full=full
        )
