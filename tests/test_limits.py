"""orbits.limits: the figures a refusal or an estimate states."""


# M31: byte counts in messages keep three significant digits
def test_format_bytes_three_significant_digits():
    from orbits.limits import format_bytes

    assert format_bytes(1234) == "1.21 KiB"  # 1234 / 1024 = 1.2051
    assert format_bytes(3.456 * 2**30) == "3.46 GiB"
    # 1000 to 1023 bytes were written 1e+03 B; 1023.6 moves to the next unit
    # (not "1024 B"), and the last unit keeps %.3g (not 285 digits)
    assert [format_bytes(x) for x in (999, 1000, 1023, 1023.6, 1024, 1023.6 * 1024)] == [
        "999 B",
        "1000 B",
        "1023 B",
        "1 KiB",
        "1 KiB",
        "1 MiB",
    ]
    assert format_bytes(1e300) == "8.88e+284 PiB"
    assert format_bytes(2**50 * 1000) == "1e+03 PiB"
