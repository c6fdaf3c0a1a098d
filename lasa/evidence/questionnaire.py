"""The study's questions, in one place: the page, the terminal survey (:func:`lasa.live.studykit.ask`) and
the analysis read them. After each way of controlling the robot: the paper's five 7-point items
(:data:`LIKERT`), the raw NASA-TLX (:data:`TLX`) and an optional comment; once, after consent, the optional
demographics (:data:`DEMOGRAPHICS`)."""

from __future__ import annotations

import dataclasses

# The paper's 7-point items: scale (the name likert.csv stores) -> the statement the participant rates.
# The page calls a condition a "way" of controlling the robot: item 5 says "way", its scale stays "Prefer".
LIKERT = {
    "Easy": "It was easy to complete the tasks with this robot.",
    "Helpful": "The robot was helpful.",
    "Precise": "I could make precise motions.",
    "Intuitive": "The robot was intuitive to control.",
    "Prefer": "I would use this way of controlling the robot again.",
}
LIKERT_RANGE = (1, 7)  # 1 = strongly disagree ... 7 = strongly agree
LIKERT_ANCHORS = ("strongly disagree", "strongly agree")


@dataclasses.dataclass(frozen=True)
class Subscale:
    """One NASA-TLX subscale: its question and the words at its two ends (0 and 100)."""

    name: str
    question: str
    low: str
    high: str


# NASA-TLX, raw (Hart 2006): six subscales rated 0-100 in steps of 5; the raw TLX is their mean.
TLX = (
    Subscale("mental", "How mentally demanding was the task?", "very low", "very high"),
    Subscale("physical", "How physically demanding was the task?", "very low", "very high"),
    Subscale("temporal", "How hurried or rushed was the pace of the task?", "very low", "very high"),
    Subscale(
        "performance",
        "How successful were you in accomplishing what you were asked to do?",
        "perfect",
        "failure",
    ),
    Subscale(
        "effort",
        "How hard did you have to work to accomplish your level of performance?",
        "very low",
        "very high",
    ),
    Subscale(
        "frustration",
        "How insecure, discouraged, irritated, stressed and annoyed were you?",
        "very low",
        "very high",
    ),
)
TLX_SUBSCALES = tuple(s.name for s in TLX)
TLX_STEP = 5  # a rating is 0, 5, ..., 100
COMMENT_CHARS = 500  # the longest optional comment (stored as given, never logged)

PREFER_NOT = "prefer not to say"
# The optional demographics: item -> its answers (each with "prefer not to say"); the form may be skipped.
DEMOGRAPHICS = {
    "age": ("18-24", "25-34", "35-44", "45-54", "55-64", "65 or older", PREFER_NOT),
    "gender": ("woman", "man", "non-binary", "another gender", PREFER_NOT),
    "handedness": ("right-handed", "left-handed", "both", PREFER_NOT),
    "joystick_experience": ("never", "a few times", "monthly", "weekly or more", PREFER_NOT),
}
DEMOGRAPHIC_QUESTIONS = {
    "age": "Your age",
    "gender": "Your gender",
    "handedness": "Which hand do you write with?",
    "joystick_experience": "How often do you use a joystick, a gamepad or play video games?",
}


def page_questions() -> dict[str, object]:
    """The questionnaire as the page shows it after a way: the Likert items, the TLX and the comment."""
    return {
        "questions": [{"scale": s, "text": t} for s, t in LIKERT.items()],
        "likert_anchors": list(LIKERT_ANCHORS),
        "tlx": [dataclasses.asdict(s) for s in TLX],
        "tlx_step": TLX_STEP,
        "comment_chars": COMMENT_CHARS,
    }


def page_demographics() -> list[dict[str, object]]:
    """The demographics form as the page shows it: per item its question and answers."""
    return [
        {"item": item, "question": DEMOGRAPHIC_QUESTIONS[item], "answers": list(answers)}
        for item, answers in DEMOGRAPHICS.items()
    ]
