#pragma once
// The lockstep protocol's message table (python/hpa_sim/messages.json, compiled into the library)
// and the generic codec that walks it. Each C++ struct that crosses the wire binds its members
// to the table's fields by name once (a Codec built from Bind and BindBit); encoding and decoding
// walk the table's fields in their declared order, applying each field's declared checks, so a
// field's name, type, unit, range and refusal text live in the table alone. The Python client
// (hpa_sim/lockstep.py) walks the same file.
//
// This header gathers the parts, each in its own header: the table (wire_table.h), a body's bytes
// (wire_bytes.h), the codec (wire_codec.h), the slots of plain members (wire_value_slots.h) and
// the bindings a codec is built from (wire_bindings.h). message_table.cc defines what they
// declare out of line.

#include "wire_bindings.h"
#include "wire_bytes.h"
#include "wire_codec.h"
#include "wire_table.h"
#include "wire_value_slots.h"
