"""Robot programs a controller loads: ABB RAPID (:mod:`.rapid`) and KUKA KRL (:mod:`.krl`).

The point-tip posts of :mod:`weldplan.io.export` describe a torch route with placeholder tool,
work-object and configuration data. The posts here describe a robot's route
(:class:`~weldplan.io.posts.program.RobotProgram`: one TCP pose and one joint vector per target,
the tool's TCP and mass, the part frame in the robot's base frame, blend radii and speeds from the
cycle-time model), so every value a controller needs is real. Each language has a small parser
of exactly what it emits (:mod:`.parse`), used by the tests to re-solve every target by forward
kinematics.
"""
