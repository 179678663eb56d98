"""The studio's Qt widgets, each bound to the document: panels, status read-outs, theme."""


def hint(html: str):
    """A small grey wrapped label: how to use a panel."""
    from PySide6 import QtWidgets

    label = QtWidgets.QLabel(f"<small>{html}</small>")
    label.setWordWrap(True)
    label.setStyleSheet("color: gray")
    return label


def nice(name: str) -> str:
    """A skeleton name as shown to people ("left_hand" -> "left hand")."""
    return name.replace("_", " ")
