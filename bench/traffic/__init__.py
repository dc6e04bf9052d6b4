"""Traffic benchmark: ADG execution of SIPP plans in a discrete-event simulation (no MQTT).

    python -m bench.traffic [--quick] [--scenario S1|S2|S3]

S1: a MovingAI-pattern warehouse (161×63) with 100 vehicles; S2: the LoRR 2023 random-32-32-20
instances against the best-known errand counts; S3: 1,000 vehicles on a 500×140 warehouse.
Figures go to bench/results/traffic_s1.json etc.
"""
