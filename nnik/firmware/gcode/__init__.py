"""G-code jobs through the generated IK: parsing, the firmware's motion logic, steps, contour error."""
