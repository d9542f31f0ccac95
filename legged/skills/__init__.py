"""The OP3's skills learned one at a time as tasks of their own, on the soccer game's physics: op3-walk and
op3-getup, drills of legged.soccer.drills made training tasks (`env`), and their configs (`config`).

Between the soccer game and the task registry: this package may import legged.soccer, and legged.tasks imports it;
soccer players use the trained skills as frozen policies (legged.soccer.walker)."""
