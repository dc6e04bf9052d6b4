"""control's broadcasts leave on a loop of their own, in the order they were handed over."""

import asyncio
import random

from control.broadcasts import _in_order


def test_sends_handed_over_together_arrive_in_order() -> None:
    arrived: list[int] = []

    async def group_send(group: str, message: dict[str, int]) -> None:
        await asyncio.sleep(random.uniform(0, 0.01))  # a slower send must not be overtaken
        arrived.append(message["n"])

    send = _in_order(group_send)

    async def main() -> None:
        await asyncio.gather(*(send("live", {"n": n}) for n in range(30)))

    asyncio.run(main())
    assert arrived == list(range(30))
