"""Control: the real-time master-control process (MQTT in/out, live fleet model, order execution) and the live page."""
