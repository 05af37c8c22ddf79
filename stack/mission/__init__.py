"""Missions: QGroundControl ``.plan`` and waypoint-list files, and tracking progress along a mission."""
