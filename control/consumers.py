"""Websocket consumers: they only join groups and forward events."""

from typing import Any

from channels.generic.websocket import AsyncJsonWebsocketConsumer

from fleet.realtime import LIVE_GROUP, remember_web_loop


class LiveConsumer(AsyncJsonWebsocketConsumer):  # type: ignore[misc]
    """Streams live fleet events (`vehicles.update`, `orders.changed`) to a logged-in browser."""

    async def connect(self) -> None:
        user = self.scope.get("user")
        if user is None or not user.is_authenticated:
            await self.close(code=4401)
            return
        remember_web_loop()
        await self.channel_layer.group_add(LIVE_GROUP, self.channel_name)
        await self.accept()

    async def disconnect(self, code: int) -> None:
        await self.channel_layer.group_discard(LIVE_GROUP, self.channel_name)

    async def fleet_event(self, message: dict[str, Any]) -> None:
        await self.send_json({"event": message["event"], "payload": message["payload"]})
