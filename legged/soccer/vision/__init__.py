"""What a soccer player sees and makes of it: the head cameras (`cameras`: ray-cast images and their agreement with
MuJoCo's renderer), the ball and goal detector on their images (`sightings`), the tracker of the player's pose and
the ball (`tracker`), a game-estimating player's estimate (`estimates`) and errors like that estimate's for state
players (`estimate_noise`)."""
