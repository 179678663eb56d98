"""The studio's Qt widgets, each bound to the document: panels, status read-outs, theme."""


def nice(name: str) -> str:
    """A skeleton name as shown to people ("left_hand" -> "left hand")."""
    return name.replace("_", " ")
