"""docs/python.md lists every field of the messages a Python stack handles: its message tables are
what `python3 -m hpa_sim.message_docs` generates from the message table (messages.json), and
every field and flag bit of the estimate (state), the command (control_output and its
body_rate_command) and the tick has a row, `mode` included. A new field in the table fails this
test until the page is regenerated:

    PYTHONPATH=python python3 -m hpa_sim.message_docs --write docs/python.md
"""

import os
import re
import unittest

from hpa_sim import lockstep, message_docs

DOCS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "docs", "python.md")


def read_docs():
    with open(DOCS, encoding="utf-8") as f:
        return f.read()


def keys_listed(text, heading):
    """The keys of the table under `heading` (a line starting with it) in text."""
    section = text[text.index(heading):]
    section = section[:section.find("\n####", 1)] if "\n####" in section[1:] else section
    return set(re.findall(r"^\| `([^`]+)` \|", section, flags=re.M))


def table_keys(struct, prefixed, prefix=""):
    """Every key a struct's fields give, flags as their bits, nested structs inline."""
    keys = set()
    for f in lockstep.STRUCTS[struct].fields:
        if f.kind == "flags":
            keys |= {b["name"] for b in f.bits}
        elif f.kind == "struct" and not f.list and not f.gate:
            keys |= table_keys(f.type.name, prefixed, prefix + f.name + "." if prefixed else "")
        else:
            keys.add(prefix + f.name)
    return keys


class MessageDocsTest(unittest.TestCase):
    def test_the_page_holds_the_generated_tables(self):
        text = read_docs()
        self.assertEqual(message_docs.replace_between_markers(text, message_docs.markdown()), text,
                         "docs/python.md's message tables differ from messages.json: run "
                         "PYTHONPATH=python python3 -m hpa_sim.message_docs --write docs/python.md")

    def test_every_field_of_the_estimate_and_the_command_has_a_row(self):
        text = read_docs()
        estimate = keys_listed(text, "#### The estimate")
        self.assertEqual(estimate, table_keys("state", True))
        self.assertIn("mode", estimate)
        self.assertIn("payload_lost", estimate)
        command = keys_listed(text, "#### The command")
        self.assertEqual(command, table_keys("control_output", False))
        self.assertTrue({"w_B_radps", "thrust_N", "status", "solve_time_ms", "cost"} <= command)
        self.assertEqual(keys_listed(text, "#### The tick"), table_keys("tick", True))

    def test_the_command_keys_are_the_python_command_attributes(self):
        # the command table's keys are what hpa_sim.Command takes, and what the client sends
        command = lockstep.Command([0.1, 0.2, 0.3], 5.0)
        self.assertEqual(set(vars(command)), table_keys("control_output", False))

    def test_a_new_field_changes_the_tables(self):
        fields = lockstep.TABLE["structs"]["state"]["fields"]
        fields.append({"name": "new_field_m", "type": "f64", "unit": "m", "doc": "a new field"})
        try:
            lockstep.STRUCTS["state"] = lockstep._Struct("state", lockstep.STRUCTS.get)
            self.assertIn("| `new_field_m` | f64 | m |", message_docs.markdown())
        finally:
            fields.pop()
            lockstep.STRUCTS["state"] = lockstep._Struct("state", lockstep.STRUCTS.get)


if __name__ == "__main__":
    unittest.main()
