"""Sensors that read the world the cheapest exact way (height-map look-ups, ray casts)."""
