"""Maps: site layouts with nodes, edges and stations, and the routing graph built from them."""
