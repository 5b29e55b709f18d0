"""Tests of tools/ros_idl/msg2idl.py on small .msg packages written to a temporary folder."""

import os
import shutil
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), '..'))
import msg2idl  # noqa: E402


class Msg2IdlTest(unittest.TestCase):
    def setUp(self):
        self.root = tempfile.mkdtemp(prefix='msg2idl_')
        self.out = os.path.join(self.root, 'out')

    def tearDown(self):
        shutil.rmtree(self.root)

    def package(self, name, messages):
        directory = os.path.join(self.root, name)
        os.makedirs(os.path.join(directory, 'msg'))
        for message, text in messages.items():
            with open(os.path.join(directory, 'msg', message + '.msg'), 'w') as handle:
                handle.write(text)
        return directory

    def generate(self, *packages):
        return msg2idl.main(['--out', self.out] + list(packages))

    def idl(self, package, message):
        with open(os.path.join(self.out, package, 'msg', message + '_.idl')) as handle:
            return handle.read()

    def run_failing(self, *packages):
        """Runs the tool as the build does; returns its stderr (the run must fail)."""
        script = os.path.join(os.path.dirname(__file__), '..', 'msg2idl.py')
        result = subprocess.run([sys.executable, script, '--out', self.out] + list(packages),
                                capture_output=True, text=True)
        self.assertEqual(result.returncode, 1, result.stderr)
        return result.stderr

    def test_primitive_types_arrays_and_constants(self):
        pkg = self.package('demo_msgs', {'Sample': (
            '# a comment line\n'
            'uint8 MODE_A=1  # trailing comment\n'
            'int8 OFFSET = -3\n'
            'bool ENABLED=true\n'
            'float64 GAIN=0.5\n'
            'string NAME="a # b"\n'
            'bool flag\n'
            'byte raw\n'
            'char letter\n'
            'float32 f\n'
            'float64 d 1.5\n'          # default value: not part of the wire type
            'int16 i16\n'
            'uint64 u64\n'
            'string text\n'
            'string<=10 short_text\n'
            'int32[4] fixed_values\n'
            'float32[] unbounded\n'
            'uint16[<=5] bounded\n'
            'string<=3[2] labels\n'
            'string<=3[] label_list\n')})
        self.assertEqual(self.generate(pkg), 0)
        text = self.idl('demo_msgs', 'Sample')
        for expected in (
                'module demo_msgs {', 'module msg {', 'module dds_ {',
                'module Sample_Constants {', 'const uint8 MODE_A = 1;', 'const int8 OFFSET = -3;',
                'const boolean ENABLED = TRUE;', 'const double GAIN = 0.5;',
                'const string NAME = "a # b";', '@final', 'struct Sample_ {',
                'boolean flag;', 'octet raw;', 'uint8 letter;', 'float f;', 'double d;',
                'int16 i16;', 'uint64 u64;', 'string text;', 'string<10> short_text;',
                'int32 fixed_values[4];', 'sequence<float> unbounded;', 'sequence<uint16, 5> bounded;',
                'string<3> labels[2];', 'sequence<string<3> > label_list;'):
            self.assertIn(expected, text)
        # the members keep the .msg order
        self.assertLess(text.index('boolean flag;'), text.index('octet raw;'))
        self.assertLess(text.index('int32 fixed_values[4];'), text.index('sequence<float> unbounded;'))

    def test_nested_types_are_included_and_scoped(self):
        base = self.package('base_msgs', {'Stamp': 'int32 sec\nuint32 nanosec\n'})
        top = self.package('top_msgs', {
            'Item': 'base_msgs/Stamp stamp\nuint8 value\n',
            'Batch': 'base_msgs/msg/Stamp stamp\nItem[] items\nItem[<=4] few\nItem[2] pair\n',
            'Empty': '# nothing\n'})
        self.assertEqual(self.generate(base, top), 0)
        batch = self.idl('top_msgs', 'Batch')
        self.assertIn('#include "base_msgs/msg/Stamp_.idl"', batch)
        self.assertIn('#include "top_msgs/msg/Item_.idl"', batch)
        self.assertIn('base_msgs::msg::dds_::Stamp_ stamp;', batch)
        self.assertIn('sequence<top_msgs::msg::dds_::Item_> items;', batch)
        self.assertIn('sequence<top_msgs::msg::dds_::Item_, 4> few;', batch)
        self.assertIn('top_msgs::msg::dds_::Item_ pair[2];', batch)
        self.assertNotIn('_Constants', batch)
        self.assertIn('uint8 structure_needs_at_least_one_member;', self.idl('top_msgs', 'Empty'))

    def test_bad_lines_name_file_and_line(self):
        cases = {
            'flot32 x\n': 'unknown type "flot32"',
            'int32 BadName\n': 'field name "BadName"',
            'uint8 value\nuint8 value\n': 'duplicate name "value"',
            'uint8 LIMIT=300\n': 'uint8 constant 300 outside [0, 255]',
            'int32[0] empty\n': 'array size must be a positive integer',
            'float32<=4 x\n': 'only strings take an upper bound',
            'int32\n': 'expected "<type> <name>"',
            'int32[] LIST=1\n': 'constants must be of a primitive, non-array type',
        }
        for text, message in cases.items():
            with self.subTest(text=text):
                shutil.rmtree(os.path.join(self.root, 'demo_msgs'), ignore_errors=True)
                pkg = self.package('demo_msgs', {'Bad': '# header\nuint8 fine\n' + text})
                stderr = self.run_failing(pkg)
                bad_line = 3 if 'value\nuint8 value' not in text else 4
                self.assertIn(f'{os.path.join(pkg, "msg", "Bad.msg")}:{bad_line}: ', stderr)
                self.assertIn(message, stderr)
                self.assertFalse(os.path.exists(os.path.join(self.out, 'demo_msgs')),
                                 'nothing is written when a file is bad')

    def test_unknown_and_recursive_types_are_refused(self):
        pkg = self.package('demo_msgs', {'A': 'other_msgs/Missing m\n'})
        self.assertIn('A.msg:1: unknown type "other_msgs/Missing"', self.run_failing(pkg))
        shutil.rmtree(pkg)
        pkg = self.package('demo_msgs', {'A': 'B b\n', 'B': 'A[] a\n'})
        self.assertIn('recursive type', self.run_failing(pkg))

    def test_idl_keywords_are_escaped(self):
        pkg = self.package('demo_msgs', {'Words': 'int32 module\nfloat64 object\nuint8 port\n'})
        self.assertEqual(self.generate(pkg), 0)
        text = self.idl('demo_msgs', 'Words')
        self.assertIn('int32 _module;', text)
        self.assertIn('double _object;', text)
        self.assertIn('uint8 _port;', text)

    @unittest.skipUnless(shutil.which(os.environ.get('VP_IDLC', 'idlc')), 'idlc not installed')
    def test_cyclone_idlc_compiles_the_output(self):
        base = self.package('base_msgs', {'Stamp': 'int32 sec\nuint32 nanosec\n'})
        top = self.package('top_msgs', {'Batch': (
            'uint8 KIND_A=1\nstring LABEL="x"\nbase_msgs/Stamp stamp\nint32 module\n'
            'string<=8[2] names\nfloat64[<=3] values\nbase_msgs/Stamp[] stamps\n')})
        self.assertEqual(self.generate(base, top), 0)
        c_out = os.path.join(self.root, 'c')
        for package, message in (('base_msgs', 'Stamp'), ('top_msgs', 'Batch')):
            subprocess.run([os.environ.get('VP_IDLC', 'idlc'), '-b', self.out, '-o', c_out,
                            '-I', self.out,
                            os.path.join(self.out, package, 'msg', message + '_.idl')],
                           check=True, capture_output=True)
        with open(os.path.join(c_out, 'top_msgs', 'msg', 'Batch_.h')) as handle:
            header = handle.read()
        self.assertIn('typedef struct top_msgs_msg_dds__Batch_', header)
        self.assertIn('int32_t module;', header)  # IDL's escape "_" is stripped
        self.assertIn('top_msgs_msg_dds__Batch_Constants_KIND_A 1', header)
        self.assertIn('#include "base_msgs/msg/Stamp_.h"', header)


if __name__ == '__main__':
    unittest.main()
