"""Shapes: clump templates (sphere unions) and their mass properties; later superquadrics and ellipsoids."""
