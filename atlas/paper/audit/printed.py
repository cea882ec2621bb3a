"""What the paper prints, as data: the rows of Table 2 in the text version, and Fig. 1's curved classes."""

#: the rows of Table 2 as printed in the paper (the text version holds 16 of the 24 rows):
#: class -> (dual, FF, SS, SF, FS, IF, FI, II, CC)
PAPER_TABLE2 = {
    11: (11, "5", "2", "1 2 6", "2 3 4", "-", "-", "-", "?"),
    12: (12, "5", "2", "1 6", "3 4", "-", "-", "-", "?"),
    13: (41, "5", "2 3", "1 6", "4", "-", "-", "-", "?"),
    14: (31, "4 5", "2 3 4", "1 6", "4", "-", "-", "(x)", "-"),
    15: (32, "4 5", "1 5 6", "1 6", "4", "-", "-", "x", "-"),
    16: (21, "4", "1 6", "1 5 6", "4 5", "-", "x", "-", "-"),
    22: (45, "5", "3", "4 5", "3 4", "x", "-", "-", "-"),
    23: (46, "5", "3", "3 4 5", "4", "x", "-", "-", "-"),
    24: (36, "4 5", "3 4", "3 4 5", "4", "x", "-", "(x)", "-"),
    25: (25, "4", "3 4 5", "3 4", "4 5", "x", "x", "x", "-"),
    26: (26, "4", "1 2 6", "3 4", "4 5", "x", "x", "-", "-"),
    33: (44, "4 5", "3 4", "5", "3", "-", "-", "x", "-"),
    34: (34, "3 4 5", "4", "5", "3", "-", "-", "x", "-"),
    35: (35, "3 4 5", "4", "4 5", "3 4", "-", "-", "x", "-"),
    42: (42, "4", "1 2 6", "5", "3", "-", "-", "-", "?"),
    43: (43, "4", "3 4 5", "5", "3", "-", "-", "x", "?"),
}

#: the classes with curved (K, Q-dependent) SS stability boundaries in Fig. 1 (Sec. 4.2, 6.3)
SS_CURVED = (13, 14, 23, 31, 41, 46)

#: a contact mode and the mode it becomes in the dual class (contacts swapped: SF <-> FS)
DUAL_MODES = (("FF", "FF"), ("SS", "SS"), ("SF", "FS"), ("FS", "SF"))

#: the contact modes of Table 1 (F: free, S: sliding; first letter contact 1)
MODES = ("FF", "SS", "SF", "FS")
