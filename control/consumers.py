"""Websocket consumers: they only check the user, join groups and forward events."""

import asyncio
from typing import Any

from channels.db import database_sync_to_async
from channels.generic.websocket import AsyncJsonWebsocketConsumer

from control.broadcasts import LiveViewer
from fleet import roles
from fleet.realtime import LIVE_GROUP, remember_web_loop

NOT_LOGGED_IN = 4401
NOT_PERMITTED = 4403


class LiveConsumer(AsyncJsonWebsocketConsumer):  # type: ignore[misc]
    """Streams live fleet events (`vehicles.update`, `orders.changed`) to a logged-in browser
    whose user may view operations (`fleet.roles.VIEW_OPERATIONS`); others are refused.
    While open it counts as a viewer of the live page: control builds its vehicle rows only
    while there is one (control.broadcasts.LiveAudience)."""

    viewer: LiveViewer | None = None
    _presence: "asyncio.Task[None] | None" = None

    async def connect(self) -> None:
        user = self.scope.get("user")
        if user is None or not user.is_authenticated:
            await self.close(code=NOT_LOGGED_IN)
            return
        if not await database_sync_to_async(user.has_perm)(roles.VIEW_OPERATIONS):
            await self.close(code=NOT_PERMITTED)
            return
        remember_web_loop()
        await self.channel_layer.group_add(LIVE_GROUP, self.channel_name)
        self.viewer = LiveViewer(self.channel_name)
        await self.viewer.mark()  # before the page is told it is live: rows go out from now
        self._presence = asyncio.create_task(self.viewer.keep())
        await self.accept()

    async def disconnect(self, code: int) -> None:
        if self._presence is not None:
            self._presence.cancel()
            await asyncio.gather(self._presence, return_exceptions=True)
        if self.viewer is not None:
            await self.viewer.end()
        await self.channel_layer.group_discard(LIVE_GROUP, self.channel_name)

    async def fleet_event(self, message: dict[str, Any]) -> None:
        await self.send_json({"event": message["event"], "payload": message["payload"]})

    async def fleet_json(self, message: dict[str, Any]) -> None:
        """An event encoded once by `fleet.realtime.broadcast_json`: forwarded as it is."""
        await self.send(text_data=message["text"])
