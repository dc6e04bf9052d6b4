"""Control: the real-time master-control process and the live page.

MQTT in and out, the live fleet model in memory, VDA 5050 order execution.
"""
