"""Vocabulary of the offline planner: which words name directions, speeds, moves and tricks.

Tables from phrase to meaning: directions, speed adverbs, fillers, motion verbs, tricks,
postures and shapes. The patterns that find these words in a clause are in `_phrases.py`.
"""

from __future__ import annotations

from shadowhound.planning._text import words

FAST = 0.5
SLOW = 0.2

DIRECTIONS: dict[str, str] = {}
for _canon, _words in {
    "forward": "forward|forwards|ahead|straight|straight ahead|straight forward|onward|onwards"
    "|to the front|frontward|frontwards",
    "back": "back|backward|backwards|in reverse|reverse|rearward|rearwards|to the rear",
    "left": "left|leftward|leftwards|to the left|to your left|towards the left|toward the left"
    "|to the left side|to your left side|on the left",
    "right": "right|rightward|rightwards|to the right|to your right|towards the right"
    "|toward the right|to the right side|to your right side|on the right",
    "ccw": "counterclockwise|counter clockwise|anticlockwise|anti clockwise|ccw",
    "cw": "clockwise|cw",
    "around": "around|round|the other way|the opposite way|the other direction"
    "|the opposite direction",
    "side": "sideways|sideway|to the side|sidewards|sideward",
    "backforth": "back and forth|forth and back|forward and back|back and forward|to and fro",
}.items():
    for _w in _words.split("|"):
        DIRECTIONS[_w] = _canon

ADVERBS: dict[str, float] = {
    **dict.fromkeys(
        words(
            "quickly|fast|quick|rapidly|briskly|hurriedly|swiftly|speedily|in a hurry|at full speed"
            "|full speed|at top speed",
            "|",
        ),
        0.5,
    ),
    **dict.fromkeys(
        words("slowly|slow|carefully|gently|cautiously|at a slow pace|steadily", "|"), 0.2
    ),
}

FILLERS = frozenset(
    words(
        "the a an by for of your yourself body further farther more another distance way direction"
        " in on to toward towards over exactly just some little bit slightly also too total"
        " approximately about roughly or so then whole"
    )
    + ["in place", "in total", "a little", "a bit", "or so", "from here", "on the spot"]
)


# ---- moves ----------------------------------------------------------------------------------

# verb -> (kind, implied direction, speed in m/s or None)
VERBS: dict[str, tuple[str, str, float | None]] = {
    **dict.fromkeys(
        words(
            "go|walk|move|head|drive|proceed|step|come|travel|march|continue|scoot|jog|trot|stroll"
            "|amble|cruise|keep going|keep walking|keep moving|carry on|make your way|take a step"
            "|take 1 step|take a small step|take a little step|take a big step",
            "|",
        ),
        ("move", "", None),
    ),
    **dict.fromkeys(words("run sprint dash hurry rush race"), ("move", "", FAST)),
    **dict.fromkeys(words("creep sneak tiptoe inch"), ("move", "", SLOW)),
    "advance": ("move", "forward", None),
    **dict.fromkeys(
        words("retreat|reverse|back up|back off|back away|backup", "|"), ("move", "back", None)
    ),
    **dict.fromkeys(
        words("strafe|sidestep|side step|shift|slide|shuffle|crab walk|crab", "|"),
        ("strafe", "", None),
    ),
    **dict.fromkeys(words("turn rotate spin pivot face swivel yaw twist"), ("rotate", "", None)),
}

# ---- tricks, postures, shapes ----------------------------------------------------------------

_TRICK_WORDS = {
    "hello": "hello|hi|wave|wave hello|wave hi|wave goodbye|wave bye|say hello|say hi|say hey"
    "|say goodbye|greet|greeting|greetings|shake|shake hands|shake hand|shake paw|paw|give paw"
    "|high 5",
    "stretch": "stretch|stretch out|stretch legs|stretching",
    "dance1": "dance|dance 1|first dance|1st dance|dance number 1|dance routine|dance routine 1"
    "|little dance|dancing|dance move",
    "dance2": "dance 2|second dance|2nd dance|dance number 2|dance routine 2|other dance",
    "wiggle_hips": "wiggle|wiggle hips|hip wiggle|shake hips|wiggle butt|shake butt|shake booty"
    "|wiggle bottom|twerk",
    "finger_heart": "heart|finger heart|heart shape|heart sign|love|make heart",
    "scrape": "bow|scrape|bow down",
    "content": "content|look content|be content|look happy|be happy|contentment|happy",
    "pose": "pose|strike pose|pose for photo|pose for camera|pose for picture",
    "wallow": "wallow|roll over|roll around|roll|wallow around|roll on ground|roll on floor",
    "moonwalk": "moonwalk|moon walk",
    "cross_step": "cross step|crossstep|cross steps",
    "onesided_step": "onesided step|1 sided step|1 side step|side step in place",
    "recovery_stand": "recover|recovery|recovery stand|recover yourself|get back on feet",
    "front_flip": "flip|front flip|frontflip|forward flip|flip forward|flip forwards",
    "front_jump": "jump|front jump|jump forward|jump forwards|hop|leap|jump up",
    "front_pounce": "pounce|front pounce|pounce forward",
    "left_flip": "left flip|flip left|flip to left|side flip left",
    "right_flip": "right flip|flip right|flip to right|side flip right",
    "backflip": "backflip|back flip|backwards flip|backward flip|flip backwards|flip backward"
    "|flip back",
    "handstand": "handstand|hand stand|stand on hands|stand on front legs|stand on front paws",
    "bound": "bound|bounding|bound in place",
}
# Words for the tricks robots perform (a Go2's sport-mode names). Which of them a robot offers
# is its own (Robot.tricks, the registry's body.sport): the planner is told, not this table.
TRICK_NAMES: dict[str, str] = {name.replace("_", " "): name for name in _TRICK_WORDS}
for _trick, _phrases in _TRICK_WORDS.items():
    TRICK_NAMES.update(dict.fromkeys(_phrases.split("|"), _trick))

POSTURE_SKILL = {"lie": "body.lie_down", "sit": "body.sit", "stand": "body.stand"}

SIDES = {"triangle": 3, "square": 4, "rectangle": 4, "pentagon": 5, "hexagon": 6, "octagon": 8}
# words a shape request may hold besides its side lengths, direction and speed
SHAPE_WORDS = frozenset(
    words(
        "walk go move run drive trot jog travel do make trace draw perform complete follow"
        " with each every side sides length lengths long wide shape shaped pattern path loop"
        " route is that has measuring size edge edges turning turns turn triangle square"
        " rectangle pentagon hexagon octagon triangles squares rectangles"
    )
)

# words a wait may hold besides its duration
WAIT_WORDS = frozenset(words("here there where you are still quietly put moment while"))

# words that often name things a robot is sent to ("the blue box", "the charging dock"): known
# to the spelling reader, so a typo elsewhere in "fnid the blue box" is not read into them
THING_WORDS = frozenset(
    words(
        "red green blue yellow white black orange purple pink brown grey gray silver big small"
        " large little ball box dock charger charging station person man woman child kid people"
        " fridge refrigerator chair table desk couch bed door window plant tree lamp shelf"
        " cabinet counter sink oven stove bin trash can bottle cup mug bag backpack shoe toy"
        " bowl cone robot dog cat tv television computer laptop phone keys book wall corner"
    )
)
