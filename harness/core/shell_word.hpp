#pragma once
// A string as one word that bash reads back unchanged: for the commands the harness prints or
// writes into scripts (the plan's Slurm line, `harness slurm`'s scripts, check's regenerate hint).
#include <string>

namespace dsb {

// s itself when it is only letters, digits and _@%+=:,./- ; else single-quoted ('\'' for a quote)
std::string shell_word(const std::string& s);

}  // namespace dsb
