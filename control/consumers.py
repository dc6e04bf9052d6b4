"""Websocket consumers: they only check the user, join groups and forward events."""

from typing import Any

from channels.db import database_sync_to_async
from channels.generic.websocket import AsyncJsonWebsocketConsumer

from fleet import roles
from fleet.realtime import LIVE_GROUP, remember_web_loop

NOT_LOGGED_IN = 4401
NOT_PERMITTED = 4403


class LiveConsumer(AsyncJsonWebsocketConsumer):  # type: ignore[misc]
    """Streams live fleet events (`vehicles.update`, `orders.changed`) to a logged-in browser
    whose user may view operations (`fleet.roles.VIEW_OPERATIONS`); others are refused."""

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
        await self.accept()

    async def disconnect(self, code: int) -> None:
        await self.channel_layer.group_discard(LIVE_GROUP, self.channel_name)

    async def fleet_event(self, message: dict[str, Any]) -> None:
        await self.send_json({"event": message["event"], "payload": message["payload"]})

    async def fleet_json(self, message: dict[str, Any]) -> None:
        """An event encoded once by `fleet.realtime.broadcast_json`: forwarded as it is."""
        await self.send(text_data=message["text"])
