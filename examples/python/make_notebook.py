"""Writes tutorial.ipynb from tutorial.py: the script is the source, in the "percent"
format (a line "# %%" starts a code cell, "# %% [markdown]" a markdown cell whose lines
are comments). tests/python/test_tutorial.py checks the two agree.

    python3 examples/python/make_notebook.py    # after editing tutorial.py
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def cells(script):
    out = []
    for chunk in script.split("# %%")[1:]:
        header, _, body = chunk.partition("\n")
        lines = body.strip("\n").split("\n")
        if header.strip() == "[markdown]":
            text = "\n".join(line[2:] if line.startswith("# ") else line.lstrip("#") for line in lines)
            out.append({"cell_type": "markdown", "metadata": {}, "source": text.splitlines(keepends=True)})
        else:
            out.append({"cell_type": "code", "metadata": {}, "execution_count": None, "outputs": [],
                        "source": "\n".join(lines).splitlines(keepends=True)})
    return out


def notebook(script):
    return {
        "cells": cells(script),
        "metadata": {"kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"},
                     "language_info": {"name": "python"}},
        "nbformat": 4,
        "nbformat_minor": 4,
    }


def render(script):
    return json.dumps(notebook(script), indent=1, ensure_ascii=False) + "\n"


if __name__ == "__main__":
    with open(os.path.join(HERE, "tutorial.py"), encoding="utf-8") as f:
        text = render(f.read())
    path = os.path.join(HERE, "tutorial.ipynb")
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    print(f"wrote {path}", file=sys.stderr)
