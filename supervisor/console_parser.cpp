#include "console_parser.hpp"

#include <algorithm>
#include <utility>

#include "console_args.hpp"
#include "console_commands.hpp"
#include "core/envelope.hpp"
#include "core/params.hpp"

namespace shapeform::supervisor {

namespace {

using core::params::join;

// ---------------------------------------------------------------------------------------------
// Parsing

/// The form the tokens name, its arguments checked against its parameters, parsed by the form.
Action parse_tokens(const std::vector<Token>& t, const core::CompiledCommand& current) {
  const std::string& word = t.front().text;
  const CommandSpec* c = find_command(word);
  if (c == nullptr) fail("unknown command '" + word + "' (try 'help')");
  if (!c->has_sub()) {
    const FormSpec& f = c->forms.front();
    return f.parse(Args(word, t, 1, c->params(f), f.max_positionals()), current);
  }
  if ((t.size() < 2 || t[1].is_pair) && !c->bare.empty()) {
    const FormSpec& f = *c->form(c->bare);
    return f.parse(Args(c->words(f), t, 1, c->params(f), f.max_positionals()), current);
  }
  if (t.size() < 2 || t[1].is_pair) fail(word + ": expected " + c->expected);
  const FormSpec* f = c->form(t[1].text);
  if (f == nullptr) {
    std::vector<std::string> subs;
    for (const FormSpec& each : c->forms) subs.push_back(each.sub);
    fail(word + ": unknown " + c->noun + " '" + t[1].text + "' (expected " + join(subs, ", ") + ")");
  }
  return f->parse(Args(c->words(*f), t, 2, c->params(*f), f->max_positionals()), current);
}

// ---------------------------------------------------------------------------------------------
// Help: every syntax line written from the registry

/// The overview's description column; a syntax may run into the two spaces before it, no further
/// (longer ones write their last optional parameters without values).
constexpr std::size_t kColumn = 60;

/// How many bracketed groups of optional parameters `ps` has.
std::size_t optional_groups(const std::vector<ParamSpec>& ps) {
  return static_cast<std::size_t>(std::count_if(
      ps.begin(), ps.end(), [](const ParamSpec& p) { return p.need == ParamSpec::Need::Optional; }));
}

/// The key=value parameters as a syntax line writes them (" m=M [cx=X cy=Y]"), the last `brief`
/// bracketed groups without their values (" [cx= cy=]").
std::string param_syntax(const std::vector<ParamSpec>& ps, std::size_t brief) {
  const std::size_t groups = optional_groups(ps);
  std::string out;
  std::size_t group = 0;
  bool open = false, bare = false;
  for (const ParamSpec& p : ps) {
    if (p.need != ParamSpec::Need::Joined && open) out += "]";
    if (p.need == ParamSpec::Need::Optional) bare = groups - group++ <= brief;
    open = p.need != ParamSpec::Need::Required;
    out += p.need == ParamSpec::Need::Optional ? " [" : " ";
    out += p.key + "=" + (open && bare ? "" : p.value);
  }
  return open ? out + "]" : out;
}

/// The syntax lines of a form: one per word it is typed with and usage, its key=value parameters
/// after the last usage.
std::vector<std::string> form_lines(const CommandSpec& c, const FormSpec& f, std::size_t brief) {
  std::vector<std::string> words = {c.words(f)};
  if (f.sub.empty()) words.insert(words.end(), c.aliases.begin(), c.aliases.end());
  std::vector<std::string> lines;
  for (const std::string& w : words) {
    for (std::size_t i = 0; i < f.usages.size(); ++i) {
      std::string line = f.usages[i].empty() ? w : w + " " + f.usages[i];
      if (i + 1 == f.usages.size()) line += param_syntax(f.params, brief);
      lines.push_back(std::move(line));
    }
  }
  return lines;
}

/// A form's syntax in the overview, on one line: its usages as alternatives ("metrics [json]",
/// "progress on|off|every S") when it has no parameters, else its lines joined by " | ".
std::string overview_syntax(const CommandSpec& c, const FormSpec& f) {
  std::string syntax;
  if (f.params.empty() && f.usages.size() > 1) {
    std::vector<std::string> alternatives;
    for (const std::string& u : f.usages)
      if (!u.empty()) alternatives.push_back(u);
    const std::string all = join(alternatives, "|");
    const bool optional = alternatives.size() < f.usages.size();
    syntax = c.words(f) + " " + (optional ? "[" + all + "]" : all);
  } else {
    for (std::size_t brief = 0; brief <= optional_groups(f.params); ++brief) {
      syntax = join(form_lines(c, f, brief), " | ");
      if (syntax.size() <= kColumn) break;
    }
  }
  if (syntax.size() <= kColumn) return syntax;
  // Too long for the column ("safety keep_out add circle X,Y R|add polygon ..."): the usages' first
  // words and "...", the page (`help WORD`) has them whole.
  std::vector<std::string> first;
  for (const std::string& u : f.usages) {
    const std::string w = u.substr(0, u.find(' '));
    if (!w.empty() && std::find(first.begin(), first.end(), w) == first.end()) first.push_back(w);
  }
  return c.words(f) + " " + join(first, "|") + " ..." + param_syntax(f.params, optional_groups(f.params));
}

std::string overview() {
  std::vector<std::pair<std::string, std::string>> rows;  // syntax, description
  for (const CommandSpec& c : command_specs()) {
    for (const FormSpec& f : c.forms) {
      if (f.summary.empty() && !rows.empty())
        rows.back().first += " | " + overview_syntax(c, f);
      else
        rows.emplace_back(overview_syntax(c, f), f.summary);
    }
    if (!c.shared.empty()) rows.emplace_back(c.word + " ..." + param_syntax(c.shared, 0), c.shared_summary);
  }
  std::string text = "Commands (key=value parameters in any order; `help COMMAND` for details):\n";
  for (const auto& [syntax, description] : rows)
    text += syntax + std::string(kColumn - 2 - std::min(syntax.size(), kColumn - 2), ' ') + "  " +
            description + "\n";
  return text + "Lines starting with # are comments. Quote values containing spaces: dir=\"a b\".\n";
}

std::string details(const CommandSpec& c) {
  std::string text;
  for (const FormSpec& f : c.forms)
    for (const std::string& line : form_lines(c, f, 0)) text += line + "\n";
  if (!c.shared.empty()) text += "  and on every " + c.noun + ":" + param_syntax(c.shared, 0) + "\n";
  return text + c.details;
}

// ---------------------------------------------------------------------------------------------
// Tab completion

/// What may follow the tokens of command `c`: its second words, or its values and the parameters
/// not given yet.
std::vector<std::string> offers(const CommandSpec& c, const std::vector<Token>& t) {
  std::vector<std::string> offer;
  const FormSpec* f = &c.forms.front();
  if (c.has_sub()) {
    if (t.size() == 1) {
      for (const FormSpec& each : c.forms) offer.push_back(each.sub);
      return offer;
    }
    f = t[1].is_pair ? nullptr : c.form(t[1].text);
    if (f == nullptr) return offer;
  } else if (t.size() == 1) {
    offer = c.offers_commands ? command_words() : f->values();
  }
  for (const ParamSpec& p : c.params(*f)) {
    bool given = false;  // a parameter is offered once
    for (const Token& tok : t) given = given || (tok.is_pair && tok.key == p.key);
    if (!given) offer.push_back(p.key + "=");
  }
  return offer;
}

}  // namespace

ParseResult parse_command(std::string_view line, const core::CompiledCommand& current) {
  ParseResult result{NoOp{}, {}};
  std::vector<Token> tokens;
  result.error = tokenize(line, tokens);
  if (!result.ok() || tokens.empty()) return result;
  try {
    result.action = parse_tokens(tokens, current);
    // Every new command keeps to its envelope, as the config loader and the agents' receiver check it.
    if (const auto* set = std::get_if<SetCommand>(&result.action)) {
      const auto problems = core::envelope_problems(set->command);
      if (!problems.empty()) fail(tokens.front().text + ": " + core::envelope_text(problems));
    }
  } catch (const ParseError& e) {
    result.action = NoOp{};
    result.error = e.message;
  }
  return result;
}

bool has_help(std::string_view word) { return find_command(word) != nullptr; }

std::vector<std::string> command_words() {
  std::vector<std::string> words;
  for (const CommandSpec& c : command_specs()) {
    words.push_back(c.word);
    words.insert(words.end(), c.aliases.begin(), c.aliases.end());
  }
  return words;
}

std::string help_text(std::string_view command) {
  if (command.empty()) return overview();
  if (const CommandSpec* c = find_command(command)) return details(*c);
  return "no help for '" + std::string(command) + "' (try 'help')\n";
}

Completion complete(std::string_view before_cursor) {
  std::vector<Token> tokens;
  Completion c;
  // Complete only outside quotes: an unterminated quote is an expression being typed.
  if (!tokenize(before_cursor, tokens).empty()) return c;
  const bool new_word = before_cursor.empty() || is_space(before_cursor.back());
  std::string word;
  if (!new_word && !tokens.empty()) {
    word = tokens.back().text;
    tokens.pop_back();
  }
  c.start = before_cursor.size() - word.size();
  if (word.find('=') != std::string::npos || word.find('"') != std::string::npos) return c;  // a value
  std::vector<std::string> offer;
  if (tokens.empty())
    offer = command_words();
  else if (const CommandSpec* command = find_command(tokens[0].text))
    offer = offers(*command, tokens);
  for (const std::string& o : offer)
    if (o.rfind(word, 0) == 0) c.candidates.push_back(o);
  std::sort(c.candidates.begin(), c.candidates.end());
  c.candidates.erase(std::unique(c.candidates.begin(), c.candidates.end()), c.candidates.end());
  return c;
}

}  // namespace shapeform::supervisor
