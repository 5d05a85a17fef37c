"""Shapes: clump templates (sphere unions) and their mass properties; 2D superquadrics (Miyata §2.3: mass properties and the
geometric-potential contact with circles of curvature); later ellipsoids."""
