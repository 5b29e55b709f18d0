#!/usr/bin/python3
"""msg2idl: ROS 2 .msg files -> the DDS IDL of their wire types, for Cyclone's idlc.

ROS 2 middlewares name the DDS type of <pkg>/msg/<T> "<pkg>::msg::dds_::<T>_" and serialise it
as plain CDR (XCDR1) with final extensibility and no key. This tool writes, for every message of
the given packages, <out>/<pkg>/msg/<T>_.idl holding that struct, the way ROS 2's
rosidl_generator_dds_idl lays it out:

    module <pkg> { module msg { module dds_ {
      module <T>_Constants { const <type> <NAME> = <value>; ... };   (only when there are any)
      @final struct <T>_ { <members in .msg order> };
    }; }; };

with `#include "<dep>/msg/<D>_.idl"` for every nested type. Types: bool -> boolean,
byte -> octet, char -> uint8, float32 -> float, float64 -> double, intN/uintN -> intN/uintN,
string -> string, string<=N -> string<N>, wstring -> wstring; T[N] -> an array, T[] ->
sequence<T>, T[<=N] -> sequence<T, N>; a nested type -> <dep>::msg::dds_::<D>_. A message with
no field gets rosidl's placeholder `uint8 structure_needs_at_least_one_member`.

Differences from rosidl_generator_dds_idl, none of which changes the bytes on the wire or the
type name: members and constants keep their .msg names (rosidl appends "_"; XCDR1 carries no
names, and names that collide with an IDL keyword are escaped with IDL's leading "_", which
the compiler strips), integer types keep their explicit IDL4 spelling (int8 rather than octet,
so that the C type keeps its sign), and default values are not emitted (rosidl drops them too).

Rules checked (ROS 2 "About interfaces"): package and field names lower-case alphanumeric with
single underscores between words, starting with a letter; constant names the same in upper
case; message names CamelCase; constants only of primitive types; array and string bounds
positive integers; integer constants within their type's range; no duplicate names; nested
types must exist among the packages given. Any violation stops the run with
"<file>:<line>: <what>" on stderr and exit status 1.

Usage: msg2idl.py --out DIR PACKAGE_DIR...   (PACKAGE_DIR/msg/*.msg; the package name is the
folder's name). Standard library only, run by /usr/bin/python3 at build time.
"""

import argparse
import os
import re
import sys

PRIMITIVES = {
    'bool': 'boolean',
    'byte': 'octet',
    'char': 'uint8',
    'float32': 'float',
    'float64': 'double',
    'int8': 'int8',
    'uint8': 'uint8',
    'int16': 'int16',
    'uint16': 'uint16',
    'int32': 'int32',
    'uint32': 'uint32',
    'int64': 'int64',
    'uint64': 'uint64',
    'string': 'string',
    'wstring': 'wstring',
}

INTEGER_RANGES = {
    'byte': (0, 255),
    'char': (0, 255),
    'int8': (-2**7, 2**7 - 1),
    'uint8': (0, 2**8 - 1),
    'int16': (-2**15, 2**15 - 1),
    'uint16': (0, 2**16 - 1),
    'int32': (-2**31, 2**31 - 1),
    'uint32': (0, 2**32 - 1),
    'int64': (-2**63, 2**63 - 1),
    'uint64': (0, 2**64 - 1),
}

# IDL 4.2 keywords: identifiers collide with them case-insensitively.
IDL_KEYWORDS = {
    k.lower() for k in (
        'abstract any alias attribute bitfield bitmask bitset boolean case char component '
        'connector const consumes context custom default double exception emits enum eventtype '
        'factory FALSE finder fixed float getraises getter home import in inout interface local '
        'long manages map mirrorport module multiple native Object octet oneway out primarykey '
        'private port porttype provides public publishes raises readonly setraises setter '
        'sequence short string struct supports switch TRUE truncatable typedef typeid typename '
        'typeprefix unsigned union uses ValueBase valuetype void wchar wstring int8 uint8 int16 '
        'int32 int64 uint16 uint32 uint64').split()
}

PACKAGE_NAME = re.compile(r'^[a-z][a-z0-9]*(_[a-z0-9]+)*$')
FIELD_NAME = PACKAGE_NAME
CONSTANT_NAME = re.compile(r'^[A-Z][A-Z0-9]*(_[A-Z0-9]+)*$')
MESSAGE_NAME = re.compile(r'^[A-Z][A-Za-z0-9]*$')
# <base>[<=N]? then an optional array suffix [N], [] or [<=N]
TYPE_SYNTAX = re.compile(
    r'^(?P<base>[A-Za-z][A-Za-z0-9_/]*)(?:<=(?P<strbound>[0-9]+))?'
    r'(?:\[(?P<array>(?:<=)?[0-9]*)\])?$')


class MsgError(Exception):
    """A problem in a .msg file, at a line (0 when it concerns the whole file)."""

    def __init__(self, path, line, what):
        super().__init__(f'{path}:{line}: {what}' if line else f'{path}: {what}')


class FieldType:
    def __init__(self, base, string_bound=None, array=None, array_size=None):
        self.base = base                  # primitive name, or (package, message)
        self.string_bound = string_bound  # N of string<=N
        self.array = array                # None, 'fixed', 'sequence', 'bounded'
        self.array_size = array_size      # N of [N] or [<=N]

    def is_primitive(self):
        return isinstance(self.base, str)


class Member:
    def __init__(self, line, ftype, name):
        self.line, self.type, self.name = line, ftype, name


class Constant:
    def __init__(self, line, ftype, name, value):
        self.line, self.type, self.name, self.value = line, ftype, name, value


class Message:
    def __init__(self, package, name, path):
        self.package, self.name, self.path = package, name, path
        self.members = []
        self.constants = []


def strip_comment(text):
    """Removes a # comment, leaving # inside a quoted string alone."""
    quote = None
    for i, ch in enumerate(text):
        if quote:
            if ch == '\\':
                continue
            if ch == quote:
                quote = None
        elif ch in ('"', "'"):
            quote = ch
        elif ch == '#':
            return text[:i]
    return text


def positive_bound(text, what, path, line):
    if not text.isdigit() or int(text) <= 0:
        raise MsgError(path, line, f'{what} must be a positive integer, got "{text}"')
    return int(text)


def parse_type(text, package, path, line):
    match = TYPE_SYNTAX.match(text)
    if not match:
        raise MsgError(path, line, f'malformed type "{text}"')
    base = match.group('base')
    string_bound = None
    if match.group('strbound') is not None:
        if base not in ('string', 'wstring'):
            raise MsgError(path, line, f'only strings take an upper bound "<=", not "{base}"')
        string_bound = positive_bound(match.group('strbound'), 'string bound', path, line)
    if base in PRIMITIVES:
        resolved = base
    else:
        parts = base.split('/')
        if len(parts) == 1:
            resolved = (package, parts[0])
        elif len(parts) == 2:
            resolved = (parts[0], parts[1])
        elif len(parts) == 3 and parts[1] == 'msg':
            resolved = (parts[0], parts[2])
        else:
            raise MsgError(path, line, f'malformed type "{text}" (expected pkg/Message)')
        if not PACKAGE_NAME.match(resolved[0]) or not MESSAGE_NAME.match(resolved[1]):
            raise MsgError(path, line, f'unknown type "{base}"')
    array = match.group('array')
    if array is None:
        return FieldType(resolved, string_bound)
    if array == '':
        return FieldType(resolved, string_bound, 'sequence')
    if array.startswith('<='):
        return FieldType(resolved, string_bound, 'bounded',
                         positive_bound(array[2:], 'sequence bound', path, line))
    return FieldType(resolved, string_bound, 'fixed',
                     positive_bound(array, 'array size', path, line))


def parse_constant_value(ftype, text, path, line):
    base = ftype.base
    text = text.strip()
    if text == '':
        raise MsgError(path, line, 'constant without a value')
    if base == 'bool':
        lowered = text.lower()
        if lowered in ('true', '1'):
            return True
        if lowered in ('false', '0'):
            return False
        raise MsgError(path, line, f'bool constant must be true or false, got "{text}"')
    if base in INTEGER_RANGES:
        try:
            value = int(text, 0)
        except ValueError:
            raise MsgError(path, line, f'{base} constant must be an integer, got "{text}"')
        low, high = INTEGER_RANGES[base]
        if not low <= value <= high:
            raise MsgError(path, line, f'{base} constant {value} outside [{low}, {high}]')
        return value
    if base in ('float32', 'float64'):
        try:
            return float(text)
        except ValueError:
            raise MsgError(path, line, f'{base} constant must be a number, got "{text}"')
    # strings: optionally quoted
    if len(text) >= 2 and text[0] == text[-1] and text[0] in ('"', "'"):
        text = text[1:-1]
    if ftype.string_bound is not None and len(text.encode()) > ftype.string_bound:
        raise MsgError(path, line, f'string constant longer than its bound {ftype.string_bound}')
    return text


def parse_msg(path, package, text):
    name = os.path.splitext(os.path.basename(path))[0]
    if not MESSAGE_NAME.match(name):
        raise MsgError(path, 0, f'message name "{name}" must be CamelCase (letters and digits)')
    message = Message(package, name, path)
    seen = set()
    for number, raw in enumerate(text.splitlines(), start=1):
        line = strip_comment(raw).strip()
        if not line:
            continue
        parts = line.split(None, 1)
        if len(parts) < 2:
            raise MsgError(path, number, f'expected "<type> <name>", got "{line}"')
        ftype = parse_type(parts[0], package, path, number)
        rest = parts[1]
        if '=' in rest:  # constant: NAME=value (spaces around = allowed)
            cname, value = rest.split('=', 1)
            cname = cname.strip()
            if not CONSTANT_NAME.match(cname):
                raise MsgError(path, number,
                               f'constant name "{cname}" must be upper case (A-Z, 0-9, _)')
            if not ftype.is_primitive() or ftype.array:
                raise MsgError(path, number, 'constants must be of a primitive, non-array type')
            if ftype.base == 'wstring':
                raise MsgError(path, number, 'wstring constants are not supported')
            if cname in seen:
                raise MsgError(path, number, f'duplicate name "{cname}"')
            seen.add(cname)
            message.constants.append(Constant(number, ftype,
                                              cname, parse_constant_value(ftype, value, path,
                                                                          number)))
            continue
        fname = rest.split(None, 1)[0]  # anything after the name is a default value
        if not FIELD_NAME.match(fname):
            raise MsgError(path, number, f'field name "{fname}" must be lower case words '
                           'joined by single underscores, starting with a letter')
        if fname in seen:
            raise MsgError(path, number, f'duplicate name "{fname}"')
        seen.add(fname)
        message.members.append(Member(number, ftype, fname))
    if not message.members:
        message.members.append(Member(0, FieldType('uint8'),
                                      'structure_needs_at_least_one_member'))
    return message


def load_packages(package_dirs):
    """Parses every <dir>/msg/*.msg; returns {(package, name): Message}."""
    messages = {}
    for directory in package_dirs:
        package = os.path.basename(os.path.normpath(directory))
        if not PACKAGE_NAME.match(package):
            raise MsgError(directory, 0, f'package name "{package}" must be lower case words')
        msg_dir = os.path.join(directory, 'msg')
        if not os.path.isdir(msg_dir):
            raise MsgError(directory, 0, 'no msg/ folder')
        for entry in sorted(os.listdir(msg_dir)):
            if not entry.endswith('.msg'):
                continue
            path = os.path.join(msg_dir, entry)
            with open(path, encoding='utf-8') as handle:
                message = parse_msg(path, package, handle.read())
            messages[(package, message.name)] = message
    return messages


def check_references(messages):
    for message in messages.values():
        for member in message.members:
            base = member.type.base
            if not member.type.is_primitive() and base not in messages:
                raise MsgError(message.path, member.line,
                               f'unknown type "{base[0]}/{base[1]}" (not among the packages given)')
    # a message may not contain itself, directly or through others
    state = {}

    def visit(key, chain):
        if state.get(key) == 'done':
            return
        if state.get(key) == 'visiting':
            message = messages[chain[0]]
            names = ' -> '.join(f'{p}/{n}' for p, n in chain + [key])
            raise MsgError(message.path, 0, f'recursive type: {names}')
        state[key] = 'visiting'
        for member in messages[key].members:
            if not member.type.is_primitive():
                visit(member.type.base, chain + [key])
        state[key] = 'done'

    for key in messages:
        visit(key, [])


def idl_identifier(name):
    return '_' + name if name.lower() in IDL_KEYWORDS else name


def idl_base_type(ftype):
    if ftype.is_primitive():
        name = PRIMITIVES[ftype.base]
        if ftype.string_bound is not None:
            name += f'<{ftype.string_bound}>'
        return name
    package, message = ftype.base
    return f'{package}::msg::dds_::{message}_'


def idl_literal(ftype, value):
    base = ftype.base
    if base == 'bool':
        return 'TRUE' if value else 'FALSE'
    if base in INTEGER_RANGES:
        return str(value)
    if base in ('float32', 'float64'):
        return repr(value)
    escaped = value.replace('\\', '\\\\').replace('"', '\\"')
    return f'"{escaped}"'


def member_declaration(member):
    base = idl_base_type(member.type)
    name = idl_identifier(member.name)
    if member.type.array == 'fixed':
        return f'{base} {name}[{member.type.array_size}];'
    if member.type.array in ('sequence', 'bounded'):
        inner = base + (' ' if base.endswith('>') else '')
        bound = f', {member.type.array_size}' if member.type.array == 'bounded' else ''
        return f'sequence<{inner}{bound}> {name};'
    return f'{base} {name};'


def render(message):
    pkg, name = message.package, message.name
    guard = f'__{pkg}__msg__{name}__idl__'
    out = [
        f'// generated by tools/ros_idl/msg2idl.py from {pkg}/msg/{name}.msg: the DDS wire type',
        '// that ROS 2 middlewares use for this message. Do not edit.',
        f'#ifndef {guard}',
        f'#define {guard}',
        '',
    ]
    includes = sorted({m.type.base for m in message.members if not m.type.is_primitive()})
    for dep_pkg, dep_name in includes:
        out.append(f'#include "{dep_pkg}/msg/{dep_name}_.idl"')
    if includes:
        out.append('')
    out += [f'module {pkg} {{', '  module msg {', '    module dds_ {']
    if message.constants:
        out.append(f'      module {name}_Constants {{')
        for constant in message.constants:
            out.append(f'        const {idl_base_type(constant.type)} '
                       f'{idl_identifier(constant.name)} = '
                       f'{idl_literal(constant.type, constant.value)};')
        out.append('      };')
    out += ['      @final', f'      struct {name}_ {{']
    for member in message.members:
        out.append('        ' + member_declaration(member))
    out += ['      };', '    };', '  };', '};', '', f'#endif  // {guard}', '']
    return '\n'.join(out)


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, 'w', encoding='utf-8') as handle:
        handle.write(text)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--out', required=True, help='output folder (<out>/<pkg>/msg/<T>_.idl)')
    parser.add_argument('packages', nargs='+', help='package folders holding msg/*.msg')
    args = parser.parse_args(argv)
    try:
        messages = load_packages(args.packages)
        check_references(messages)
    except MsgError as error:
        print(f'msg2idl: {error}', file=sys.stderr)
        return 1
    except OSError as error:
        print(f'msg2idl: {error}', file=sys.stderr)
        return 1
    for (package, name), message in sorted(messages.items()):
        write(os.path.join(args.out, package, 'msg', f'{name}_.idl'), render(message))
    return 0


if __name__ == '__main__':
    sys.exit(main())
