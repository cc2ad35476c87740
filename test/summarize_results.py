#!/usr/bin/python3
"""Summarises every gtest/rostest JUnit XML under a results folder.

Prints the failed test cases, then a last line `N passed, N failed` (skipped tests are
reported separately). Exit code 1 if anything failed or no test ran at all.
Usage: summarize_results.py <build/test_results> [extra failures]
"""
import glob
import os
import sys
import xml.etree.ElementTree as ET


def main():
    root = sys.argv[1]
    extra_failures = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    passed = failed = skipped = 0
    failures = []
    files = sorted(glob.glob(os.path.join(root, "**", "*.xml"), recursive=True))
    for path in files:
        try:
            tree = ET.parse(path)
        except ET.ParseError as e:
            failed += 1
            failures.append(f"{path}: unreadable result file ({e})")
            continue
        for case in tree.iter("testcase"):
            name = f"{case.get('classname', '')}.{case.get('name', '')}"
            if case.find("failure") is not None or case.find("error") is not None:
                failed += 1
                node = case.find("failure")
                if node is None:
                    node = case.find("error")
                msg = (node.get("message") or node.text or "").strip().splitlines()
                failures.append(f"{name} ({os.path.relpath(path, root)}): {msg[0] if msg else ''}")
            elif case.find("skipped") is not None or case.get("status") == "notrun":
                skipped += 1
            else:
                passed += 1
    failed += extra_failures
    print(f"[tests] {len(files)} result files under {root}")
    for f in failures:
        print(f"[tests] FAILED {f}")
    if skipped:
        print(f"[tests] {skipped} skipped")
    print(f"{passed} passed, {failed} failed")
    return 1 if failed or passed == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
